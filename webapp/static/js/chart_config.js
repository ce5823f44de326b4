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
  if (window.Plotly) window.Plotly.setPlotConfig(base);
})();
