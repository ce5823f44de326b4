// Every chart's Plotly options, loaded right after plotly.min.js: nothing on a chart links to or
// sends data to a third party. plotly.js 4 shows by default a "Share chart..." button that posts
// the chart's data (a patient's) to Plotly's cloud (`showSendToCloud`, `plotlyServerURL`) and a
// logo linking to plotly.com (`displaylogo`); both are off here, for every chart of the page.
(function () {
  const base = {
    displaylogo: false,
    watermark: false,
    showSendToCloud: false,
    plotlyServerURL: "",
    modeBarButtonsToRemove: ["sendChartToCloud"],
    responsive: true,
  };
  window.chartConfig = (extra) => Object.assign({}, base, extra || {});
  // The layout of a chart over session dates. `axis` (webapp.patients.progress.date_axis): a
  // range with a margin around the sessions and whole-day ticks labelled "12 Nov", so a single
  // session never gives sub-second ticks. The legend sits above the plot, in its own margin,
  // where it covers neither a line nor an axis title (Plotly 3 reads titles only as { text }).
  window.progressLayout = (axis, xTitle, yTitle, extra = {}) => ({
    margin: { t: 40, r: 10, b: 50, l: 60 },
    legend: { orientation: "h", x: 1, xanchor: "right", y: 1.02, yanchor: "bottom" },
    ...extra,
    xaxis: { type: "date", title: { text: xTitle }, range: axis.range, tick0: axis.tick0, dtick: axis.dtick, tickformat: axis.tickformat, ...(extra.xaxis || {}) },
    yaxis: { title: { text: yTitle }, ...(extra.yaxis || {}) },
  });
  if (window.Plotly) window.Plotly.setPlotConfig(base);
})();
