// While a worker recognises the exercise of a recording, follow its progress through the
// recording's status endpoint; reload when it ends, to show the suggestion or the choice.
(function () {
  const box = document.getElementById("recognition");
  if (!box) return;
  const underWay = (s) => s === "queued" || s === "running";
  if (!underWay(box.dataset.recognition)) return;
  const bar = box.querySelector(".bar");
  const percent = document.getElementById("recognition-percent");
  async function poll() {
    try {
      const response = await fetch(box.dataset.statusUrl, { headers: { Accept: "application/json" } });
      if (response.ok) {
        const answer = await response.json();
        bar.style.width = answer.progress + "%";
        box.querySelector(".progress").setAttribute("aria-valuenow", answer.progress);
        percent.textContent = answer.progress;
        if (answer.status || !underWay(answer.recognition)) { window.location.reload(); return; }
      }
    } catch (error) { /* network hiccup: try again */ }
    setTimeout(poll, 1000);
  }
  setTimeout(poll, 500);
})();
