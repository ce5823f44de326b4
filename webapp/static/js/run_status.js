// Poll the analysis status while a run is queued or running; reload when it ends.
(function () {
  const box = document.getElementById("run-status");
  if (!box) return;
  // What the worker reports besides the pipeline's stage labels (as the stage_words filter).
  const STAGE_WORDS = { loading: "loading the recording", done: "saving the result" };
  const active = (s) => s === "queued" || s === "running";
  if (!active(box.dataset.status)) return;
  const bar = box.querySelector(".bar");
  const state = document.getElementById("run-state");
  const stage = document.getElementById("run-stage");
  async function poll() {
    try {
      const response = await fetch(box.dataset.statusUrl, { headers: { Accept: "application/json" } });
      if (response.ok) {
        const run = await response.json();
        bar.style.width = run.progress + "%";
        box.querySelector(".progress").setAttribute("aria-valuenow", run.progress);
        state.textContent = run.status;
        stage.textContent = run.stage ? `· ${STAGE_WORDS[run.stage] ?? run.stage}` : "";
        if (!active(run.status)) { window.location.reload(); return; }
      }
    } catch (error) { /* network hiccup: try again */ }
    setTimeout(poll, 1000);
  }
  setTimeout(poll, 500);
})();
