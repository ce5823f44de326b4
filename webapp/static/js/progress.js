// Progression charts of one patient over sessions (patients:progress JSON endpoint): score, range
// of motion and level per body part (one line per exercise and body part: sessions of different
// exercises are never joined), repetitions against the prescribed target, an adherence calendar.
(async function () {
  const box = document.getElementById("progress");
  if (!box || !window.Plotly) return;
  const { points: all, labels = {} } = await fetch(box.dataset.url).then((r) => r.json());
  const prescriptions = JSON.parse(document.getElementById("prescriptions").textContent);
  if (!all.length) { document.getElementById("progress-empty").hidden = false; box.dataset.ready = "1"; return; }
  const config = window.chartConfig();
  const layout = (title, extra = {}) => ({ margin: { t: 10, r: 10, b: 40, l: 60 }, xaxis: { title: { text: "date" } }, yaxis: { title: { text: title } }, legend: { orientation: "h" }, ...extra });
  const select = document.getElementById("exercise-filter");
  [...new Set(all.map((p) => p.exercise_name || "?"))].forEach((name) => select.add(new Option(name, name)));

  // One line per exercise and body part; the exercise is named when several are shown.
  function perJoint(points, field, several) {
    const lines = [];
    const byExercise = {};
    points.forEach((p) => { (byExercise[p.exercise_name || "?"] ??= []).push(p); });
    for (const [exercise, ps] of Object.entries(byExercise)) {
      const joints = [...new Set(ps.flatMap((p) => Object.keys(p[field] || {})))];
      for (const j of joints) {
        const part = labels[j] ?? j;
        lines.push({ x: ps.map((p) => p.date.slice(0, 10)), y: ps.map((p) => (p[field] || {})[j] ?? null), name: several ? `${exercise} · ${part}` : part, mode: "lines+markers", connectgaps: true });
      }
    }
    return lines;
  }

  function adherence(points) {
    // Weeks (columns) x weekdays (rows), counting sessions per day over the last 12 weeks.
    const today = new Date();
    const monday = new Date(today); monday.setDate(today.getDate() - ((today.getDay() + 6) % 7) - 7 * 11);
    const z = Array.from({ length: 7 }, () => Array(12).fill(0));
    points.forEach((p) => {
      const day = Math.floor((new Date(p.date) - monday) / 86400000);
      if (day >= 0 && day < 84) z[day % 7][Math.floor(day / 7)] += 1;
    });
    const weeks = Array.from({ length: 12 }, (_, w) => { const d = new Date(monday); d.setDate(d.getDate() + 7 * w); return d.toISOString().slice(0, 10); });
    return [{ type: "heatmap", z, x: weeks, y: ["Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"], colorscale: [[0, "#f3f5f8"], [1, "#2da44e"]], zmin: 0, showscale: false, xgap: 2, ygap: 2 }];
  }

  // Goals (dashed, labelled "goal" with the unit) from the first session shown to the goal's date.
  function goalLines(chart, chosen, start) {
    const box = document.getElementById("goal-lines");
    const goals = box ? JSON.parse(box.textContent) : [];
    return goals.filter((g) => g.chart === chart && (!chosen || g.exercise === chosen)).map((g) => ({
      x: [start || g.by, g.by], y: [g.target, g.target], name: `${g.text} · ${g.exercise}`,
      mode: "lines+text", text: ["", g.text], textposition: "top left", line: { dash: "dash", color: "#6e7781" },
      hovertemplate: `${g.label}: ${g.text} by ${g.by}<extra></extra>`,
    }));
  }

  function draw() {
    const chosen = select.value;
    const points = chosen ? all.filter((p) => (p.exercise_name || "?") === chosen) : all;
    const dates = points.map((p) => p.date.slice(0, 10));
    const byExercise = {};
    points.forEach((p) => { (byExercise[p.exercise_name || "?"] ??= []).push(p); });
    const scores = Object.entries(byExercise).map(([name, ps]) => ({ x: ps.map((p) => p.date.slice(0, 10)), y: ps.map((p) => p.score), name, mode: "lines+markers" }));
    const several = Object.keys(byExercise).length > 1;
    Plotly.react("chart-score", [...scores, ...goalLines("score", chosen, dates[0])], layout("score (0–100)", { yaxis: { title: { text: "score (0–100)" }, range: [0, 100] } }), config);
    Plotly.react("chart-rom", perJoint(points, "range_of_motion", several), layout("range of motion (degrees)"), config);
    Plotly.react("chart-gamma", perJoint(points, "gamma", several), layout("level (0–1)", { yaxis: { title: { text: "level (0–1)" }, range: [0, 1.05] } }), config);
    const reps = [{ type: "bar", x: dates, y: points.map((p) => p.repetitions), name: "repetitions", marker: { color: "#1f6feb" } }];
    const targets = prescriptions.filter((p) => p.target_repetitions != null && (!chosen || p.exercise === chosen)).map((p) => ({
      x: [p.start, p.end || new Date().toISOString().slice(0, 10)], y: [p.target_repetitions, p.target_repetitions],
      name: `target · ${p.exercise}`, mode: "lines", line: { dash: "dash" },
    }));
    Plotly.react("chart-reps", [...reps, ...targets], layout("repetitions (count)"), config);
    Plotly.react("chart-adherence", adherence(points), layout("day of the week", { margin: { t: 10, r: 10, b: 40, l: 60 }, xaxis: { title: { text: "week starting" } } }), config);
  }
  select.addEventListener("change", draw);
  draw();
  box.dataset.ready = "1";
})();
