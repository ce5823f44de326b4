// Progression charts of one patient, one exercise at a time (sessions of different exercises are
// never joined): score, range of motion and level of the (up to) four body parts the exercise
// moves most, repetitions against the prescribed target, an adherence calendar. The series come
// from the page (#progress-charts, built by webapp.patients.progress.progress_charts): one point
// per session placed by date, sessions of one day side by side, a whole-day date axis.
(function () {
  const box = document.getElementById("progress");
  const data = document.getElementById("progress-charts");
  if (!box || !data || !window.Plotly) return;
  const exercises = JSON.parse(data.textContent);
  const prescriptions = JSON.parse(document.getElementById("prescriptions").textContent);
  const goalBox = document.getElementById("goal-lines");
  const goals = goalBox ? JSON.parse(goalBox.textContent) : [];
  if (!exercises.length) { document.getElementById("progress-empty").hidden = false; box.dataset.ready = "1"; return; }
  const config = window.chartConfig();
  const select = document.getElementById("exercise-filter");
  exercises.forEach((ex, i) => select.add(new Option(ex.exercise, String(i))));

  // The legend sits above the plot, right-aligned: it never covers an axis title.
  const layout = (ex, yTitle, extra = {}) => window.progressLayout(ex.axis, "date of the session", yTitle, extra);
  const line = (ex, y, name, unit) => ({
    x: ex.x, y, name, mode: "lines+markers", connectgaps: true, customdata: ex.when,
    hovertemplate: `${name}: %{y:.1f}${unit}<extra>%{customdata}</extra>`,
  });
  // Goals (dashed, labelled "goal" with the unit) from the first session to the goal's date.
  const goalLines = (ex, chart) => goals.filter((g) => g.chart === chart && g.exercise === ex.exercise).map((g) => ({
    x: [ex.x[0] || g.by, g.by], y: [g.target, g.target], name: g.text,
    mode: "lines+text", text: ["", g.text], textposition: "top left", line: { dash: "dash", color: "#6e7781" },
    hovertemplate: `${g.label}: ${g.text} by ${g.by}<extra></extra>`,
  }));
  const withGoals = (ex, extra) => {
    // Widen the date axis to show a goal's date beyond the last session.
    const ends = goals.filter((g) => g.exercise === ex.exercise).map((g) => `${g.by} 23:59:59`);
    const range = [ex.axis.range[0], [ex.axis.range[1], ...ends].sort().pop()];
    const days = (new Date(range[1].replace(" ", "T")) - new Date(range[0].replace(" ", "T"))) / 86400000;
    const dtick = Math.max(ex.axis.dtick, Math.ceil(days / 8) * 86400000);  // eight ticks at most
    return { ...ex, axis: { ...ex.axis, range, dtick }, ...extra };
  };

  function adherence(ex) {
    // Weeks (columns) x weekdays (rows), counting sessions per day over the last 12 weeks.
    const today = new Date();
    const monday = new Date(today); monday.setDate(today.getDate() - ((today.getDay() + 6) % 7) - 7 * 11);
    const z = Array.from({ length: 7 }, () => Array(12).fill(0));
    ex.x.forEach((x) => {
      const day = Math.floor((new Date(x.slice(0, 10)) - monday) / 86400000);
      if (day >= 0 && day < 84) z[day % 7][Math.floor(day / 7)] += 1;
    });
    const weeks = Array.from({ length: 12 }, (_, w) => { const d = new Date(monday); d.setDate(d.getDate() + 7 * w); return d.toISOString().slice(0, 10); });
    return [{ type: "heatmap", z, x: weeks, y: ["Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"], colorscale: [[0, "#f3f5f8"], [1, "#2da44e"]], zmin: 0, showscale: false, xgap: 2, ygap: 2 }];
  }

  function draw() {
    const ex = exercises[Number(select.value) || 0];
    const shown = withGoals(ex);
    Plotly.react("chart-score", [line(ex, ex.score, "score", " of 100"), ...goalLines(ex, "score")], layout(shown, "score (0–100)", { yaxis: { range: [0, 105] } }), config);
    Plotly.react("chart-rom", ex.rom.map((p) => line(ex, p.y, p.label, "°")), layout(ex, "range of motion (°)", { yaxis: { rangemode: "tozero" } }), config);
    Plotly.react("chart-gamma", ex.gamma.map((p) => line(ex, p.y, p.label, " of 1")), layout(ex, "level (0–1)", { yaxis: { range: [0, 1.05] } }), config);
    const reps = [{ type: "bar", x: ex.x, y: ex.repetitions, name: "repetitions", marker: { color: "#1f6feb" }, customdata: ex.when, hovertemplate: "%{y} repetitions<extra>%{customdata}</extra>" }];
    const targets = prescriptions.filter((p) => p.target_repetitions != null && p.exercise === ex.exercise).map((p) => ({
      x: [p.start, p.end || new Date().toISOString().slice(0, 10)], y: [p.target_repetitions, p.target_repetitions],
      name: "prescribed target", mode: "lines", line: { dash: "dash" },
    }));
    Plotly.react("chart-reps", [...reps, ...targets], layout(ex, "repetitions (count)", { bargap: 0.6 }), config);
    Plotly.react("chart-adherence", adherence(ex), { margin: { t: 10, r: 10, b: 50, l: 60 }, xaxis: { title: { text: "week starting" } }, yaxis: { title: { text: "day of the week" } } }, config);
  }
  select.addEventListener("change", draw);
  draw();
  box.dataset.ready = "1";
})();
