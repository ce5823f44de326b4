// The training report's joint weights as a bar chart by body part.
(function () {
  const data = document.getElementById("joint-weights-data");
  const chart = document.getElementById("joint-weights-chart");
  if (!data || !chart || !window.Plotly) return;
  const weights = JSON.parse(data.textContent);
  Plotly.newPlot(chart, [{
    type: "bar", x: weights.map((w) => w.name), y: weights.map((w) => w.weight),
    marker: { color: "#1f6feb" }, hovertemplate: "%{x}: %{y:.2f}<extra></extra>",
  }], {
    margin: { t: 10, r: 10, b: 90, l: 60 },
    xaxis: { title: { text: "body part" }, automargin: true },
    yaxis: { title: { text: "weight (relative)" }, rangemode: "tozero" },
  }, window.chartConfig());
})();
