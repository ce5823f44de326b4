// Progress page: per exercise, one Plotly chart of each clinical angle's range (degrees) over
// the session dates, and one of each hand's reachable area (% of the front hemisphere). Series
// of different exercises are never joined: each exercise has its own charts.
(function () {
  const data = document.getElementById("clinical-progress-data");
  if (!data || !window.Plotly) return;
  const exercises = JSON.parse(data.textContent);
  const config = window.chartConfig();
  // Plotly 3 reads axis titles only as { text }: a bare string leaves the axis without its unit.
  const layout = (title, extra = {}) => ({ margin: { t: 10, r: 10, b: 40, l: 55 }, yaxis: { title: { text: title }, rangemode: "tozero" }, legend: { orientation: "h" }, ...extra });
  const moving = (values) => Math.max(0, ...values.filter((v) => v !== null)) >= 10;
  // Angle goals of this exercise: a dashed line at the target from the first session to the
  // goal's date, labelled "goal" with its unit (degrees).
  const goalBox = document.getElementById("goal-lines");
  const goals = goalBox ? JSON.parse(goalBox.textContent) : [];
  const goalLines = (ex) => goals.filter((g) => g.chart === "angle" && g.exercise === ex.exercise).map((g) => ({
    x: [ex.dates[0] || g.by, g.by], y: [g.target, g.target], name: `${g.text} · ${g.label}`,
    mode: "lines+text", text: ["", g.text], textposition: "top left", line: { dash: "dash" },
    hovertemplate: `${g.label}: ${g.text} by ${g.by}<extra></extra>`,
  }));
  exercises.forEach((ex) => {
    const angles = ex.angles.map((a) => ({
      x: ex.dates, y: a.range, name: a.label, mode: "lines+markers", connectgaps: false,
      visible: moving(a.range) ? true : "legendonly",
      hovertemplate: `${a.label}: %{y:.1f}°<extra>%{x}</extra>`,
    }));
    Plotly.react(`${ex.id}-angles`, [...angles, ...goalLines(ex)], layout("range of motion (°)"), config);
    if (ex.workspace.length) {
      const reach = ex.workspace.map((h) => ({ x: ex.dates, y: h.percent, name: h.label, mode: "lines+markers", hovertemplate: `${h.label}: %{y:.1f} %<extra>%{x}</extra>` }));
      Plotly.react(`${ex.id}-workspace`, reach, layout("% of the front hemisphere", { yaxis: { title: { text: "% of the front hemisphere" }, range: [0, 100] } }), config);
    }
  });
  document.getElementById("clinical-progress").dataset.ready = "1";
})();
