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
    x: ex.x, y, name: window.legendName(name), mode: "lines+markers", connectgaps: true, customdata: ex.when,
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

  // Days as whole numbers counted in the clinic's calendar: the page gives today's date and each
  // session's date in the clinic's time zone, and the arithmetic below reads them as UTC dates,
  // so neither the browser's own time zone nor the time of day ever moves a session to another day.
  const DAY_MS = 86400000;
  const dayOf = (iso) => Date.UTC(+iso.slice(0, 4), +iso.slice(5, 7) - 1, +iso.slice(8, 10)) / DAY_MS;
  const dateOf = (day) => new Date(day * DAY_MS);
  const MONTHS = ["Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"];
  const WEEKDAYS = ["Mon", "Tue", "Wed", "Thu", "Fri", "Sat", "Sun"];
  const weekday = (day) => (dateOf(day).getUTCDay() + 6) % 7;  // Monday 0
  const words = (day) => `${dateOf(day).getUTCDate()} ${MONTHS[dateOf(day).getUTCMonth()]}`;
  const today = dayOf(box.dataset.today || new Date().toISOString());
  const todayIso = dateOf(today).toISOString().slice(0, 10);

  function adherence(ex) {
    // Weeks (columns, labelled by their Monday) x weekdays (rows), sessions per day over the last
    // 12 weeks; each cell says its date when pointed at.
    const monday = today - weekday(today) - 7 * 11;
    const z = Array.from({ length: 7 }, () => Array(12).fill(0));
    ex.x.forEach((x) => {
      const day = dayOf(x) - monday;
      if (day >= 0 && day < 84) z[day % 7][Math.floor(day / 7)] += 1;
    });
    const weeks = Array.from({ length: 12 }, (_, w) => words(monday + 7 * w));
    const dates = WEEKDAYS.map((name, d) => weeks.map((_, w) => `${name} ${words(monday + 7 * w + d)} ${dateOf(monday + 7 * w + d).getUTCFullYear()}`));
    return [{
      type: "heatmap", z, x: weeks, y: WEEKDAYS, customdata: dates, hovertemplate: "%{customdata}: %{z} session(s)<extra></extra>",
      colorscale: [[0, "#f3f5f8"], [1, "#2da44e"]], zmin: 0, showscale: false, xgap: 2, ygap: 2,
    }];
  }

  function draw() {
    const ex = exercises[Number(select.value) || 0];
    const shown = withGoals(ex);
    Plotly.react("chart-score", [line(ex, ex.score, "score", " of 100"), ...goalLines(ex, "score")], layout(shown, "score (0–100)", { yaxis: { range: [0, 105] } }), config);
    Plotly.react("chart-rom", ex.rom.map((p) => line(ex, p.y, p.label, "°")), layout(ex, "range of motion (°)", { yaxis: { rangemode: "tozero" } }), config);
    Plotly.react("chart-gamma", ex.gamma.map((p) => line(ex, p.y, p.label, " of 1")), layout(ex, "level (0–1)", { yaxis: { range: [0, 1.05] } }), config);
    const reps = [{ type: "bar", x: ex.x, y: ex.repetitions, name: "repetitions", marker: { color: "#1f6feb" }, customdata: ex.when, hovertemplate: "%{y} repetitions<extra>%{customdata}</extra>" }];
    const targets = prescriptions.filter((p) => p.target_repetitions != null && p.exercise === ex.exercise).map((p) => ({
      x: [p.start, p.end || todayIso], y: [p.target_repetitions, p.target_repetitions],
      name: "prescribed target", mode: "lines", line: { dash: "dash" },
    }));
    Plotly.react("chart-reps", [...reps, ...targets], layout(ex, "repetitions (count)", { bargap: 0.6 }), config);
    Plotly.react("chart-adherence", adherence(ex), { margin: { t: 10, r: 10, b: 50, l: 60 }, xaxis: { type: "category", title: { text: "week starting (Monday)" } }, yaxis: { type: "category", autorange: "reversed", title: { text: "day of the week" } } }, config);
  }
  select.addEventListener("change", draw);
  draw();
  box.dataset.ready = "1";
})();
