// Progress page: per exercise, one Plotly chart of the range (degrees) of the (up to) four
// clinical angles the exercise moves most over the session dates, with the normal adult range as
// a band, and one of each hand's reachable area (% of the front hemisphere). Series of different
// exercises are never joined: each exercise has its own charts. One point per session placed by
// date (sessions of one day side by side), whole-day ticks (webapp.patients.progress).
(function () {
  const data = document.getElementById("clinical-progress-data");
  if (!data || !window.Plotly) return;
  const exercises = JSON.parse(data.textContent);
  const config = window.chartConfig();
  const layout = (ex, title, extra = {}) => window.progressLayout(ex.axis, "date of the session", title, extra);
  // Angle goals of this exercise: a dashed line at the target from the first session to the
  // goal's date, labelled "goal" with its unit (degrees).
  const goalBox = document.getElementById("goal-lines");
  const goals = goalBox ? JSON.parse(goalBox.textContent) : [];
  const goalLines = (ex) => goals.filter((g) => g.chart === "angle" && g.exercise === ex.exercise).map((g) => ({
    x: [ex.x[0] || g.by, g.by], y: [g.target, g.target], name: `${g.text} · ${g.label}`,
    mode: "lines+text", text: ["", g.text], textposition: "top left", line: { dash: "dash" },
    hovertemplate: `${g.label}: ${g.text} by ${g.by}<extra></extra>`,
  }));
  // The normal adult range: a grey band behind the lines, across the whole date axis.
  const band = (ex) => (ex.band ? [{
    type: "rect", xref: "paper", x0: 0, x1: 1, yref: "y", y0: ex.band.low, y1: ex.band.high,
    fillcolor: "#d0d7de", opacity: 0.35, line: { width: 0 }, layer: "below",
  }] : []);
  const bandLegend = (ex) => (ex.band ? [{
    x: [null], y: [null], name: window.legendName(ex.band.text), mode: "lines", line: { color: "#d0d7de", width: 10 }, hoverinfo: "skip",
  }] : []);
  const withGoalDates = (ex) => {
    const ends = goals.filter((g) => g.chart === "angle" && g.exercise === ex.exercise).map((g) => `${g.by} 23:59:59`);
    const range = [ex.axis.range[0], [ex.axis.range[1], ...ends].sort().pop()];
    const days = (new Date(range[1].replace(" ", "T")) - new Date(range[0].replace(" ", "T"))) / 86400000;
    return { ...ex, axis: { ...ex.axis, range, dtick: Math.max(ex.axis.dtick, Math.ceil(days / 8) * 86400000) } };
  };
  exercises.forEach((ex) => {
    const angles = ex.angles.filter((a) => a.shown).map((a) => ({
      x: ex.x, y: a.range, name: window.legendName(a.label), mode: "lines+markers", connectgaps: false, customdata: ex.when,
      hovertemplate: `${a.label}: %{y:.1f}°<extra>%{customdata}</extra>`,
    }));
    const chart = withGoalDates(ex);
    Plotly.react(`${ex.id}-angles`, [...angles, ...bandLegend(ex), ...goalLines(ex)], layout(chart, "range of motion (°)", { yaxis: { rangemode: "tozero" }, shapes: band(ex) }), config);
    if (ex.workspace.length) {
      const reach = ex.workspace.map((h) => ({ x: ex.x, y: h.percent, name: h.label, mode: "lines+markers", customdata: ex.when, hovertemplate: `${h.label}: %{y:.1f} %<extra>%{customdata}</extra>` }));
      Plotly.react(`${ex.id}-workspace`, reach, layout(ex, "% of the front hemisphere", { yaxis: { range: [0, 100] } }), config);
    }
  });
  document.getElementById("clinical-progress").dataset.ready = "1";
})();
