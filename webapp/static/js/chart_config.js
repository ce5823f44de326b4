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
  // Every legend sits above its plot, right-aligned, in a top margin Plotly grows to fit it:
  // there it covers neither a line nor an axis title. (Plotly's own place for a horizontal
  // legend, under the plot, is where the x axis's title is drawn: on a phone, where the legend
  // wraps onto many lines, the two overlap.)
  window.legendAbove = () => ({ orientation: "h", x: 1, xanchor: "right", y: 1.02, yanchor: "bottom" });
  // The layout of a chart over session dates. `axis` (webapp.patients.progress.date_axis): a
  // range with a margin around the sessions and whole-day ticks labelled "12 Nov", so a single
  // session never gives sub-second ticks (Plotly 3 reads titles only as { text }).
  window.progressLayout = (axis, xTitle, yTitle, extra = {}) => ({
    margin: { t: 40, r: 10, b: 50, l: 60 },
    legend: window.legendAbove(),
    ...extra,
    xaxis: { type: "date", title: { text: xTitle }, range: axis.range, tick0: axis.tick0, dtick: axis.dtick, tickformat: axis.tickformat, ...(extra.xaxis || {}) },
    yaxis: { title: { text: yTitle }, ...(extra.yaxis || {}) },
  });
  // A legend entry is one line and Plotly cuts off what passes the chart's edge: on a phone-wide
  // chart, long names ("Left shoulder elevation (arm to trunk) (normal 0° to 180°)") are broken
  // into lines of about 30 characters at spaces, so each entry fits the chart.
  window.legendName = (text) => {
    if (window.innerWidth > 640) return text;
    const lines = [];
    for (const word of String(text).split(" ")) {
      const last = lines.length - 1;
      if (last >= 0 && (lines[last] + " " + word).length <= 30) lines[last] += " " + word;
      else lines.push(word);
    }
    return lines.join("<br>");
  };
  if (window.Plotly) window.Plotly.setPlotConfig(base);
})();
