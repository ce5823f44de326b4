// Home page: keep "Analyses under way" and "Recent recordings" current without reloading the page.
// One request per poll (the home page's ?format=json), faster while something is running, and
// none while the tab is hidden.
(function () {
  const box = document.getElementById("active-runs");
  if (!box) return;
  const list = document.getElementById("active-list");
  const empty = document.getElementById("active-empty");
  const count = document.getElementById("active-count");
  const recentRows = document.getElementById("recent-rows");
  const showPatient = document.querySelector("#recent thead th:nth-child(2)")?.textContent === "Patient";
  const BUSY_MS = 1500, IDLE_MS = 5000;

  function element(tag, className, text) {
    const node = document.createElement(tag);
    if (className) node.className = className;
    if (text !== undefined) node.textContent = text;
    return node;
  }

  function runRow(run) {
    const item = element("li", "run");
    item.dataset.run = run.run;
    const head = element("div", "row-between");
    const link = element("a", "", `${run.patient} · ${run.exercise || "exercise to confirm"}`);
    link.href = run.url;
    head.append(link, element("span", "run-state"));
    const progress = element("div", "progress");
    progress.setAttribute("role", "progressbar");
    progress.setAttribute("aria-valuemin", "0");
    progress.setAttribute("aria-valuemax", "100");
    progress.append(element("div", "bar"));
    item.append(head, progress);
    return item;
  }

  function updateRun(item, run) {
    item.querySelector(".run-state").textContent = run.stage ? `${run.status_label} · ${run.stage}` : run.status_label;
    item.querySelector(".bar").style.width = `${run.progress}%`;
    item.querySelector(".progress").setAttribute("aria-valuenow", run.progress);
  }

  function showActive(active) {
    const seen = new Set();
    for (const run of active) {
      seen.add(run.run);
      let item = list.querySelector(`[data-run="${run.run}"]`);
      if (!item) { item = runRow(run); list.append(item); }
      updateRun(item, run);
    }
    for (const item of list.querySelectorAll(".run")) {
      if (seen.has(item.dataset.run) || item.classList.contains("finished")) continue;
      // Ended since the last poll: show it complete for a moment, then let it go.
      item.classList.add("finished");
      item.querySelector(".bar").style.width = "100%";
      item.querySelector(".run-state").textContent = "Finished";
      setTimeout(() => { item.remove(); empty.hidden = list.children.length > 0; }, 4000);
    }
    count.textContent = active.length;
    empty.hidden = list.children.length > 0;
  }

  function statusCell(r) {
    const label = r.status === "running" ? `Running ${r.progress}%` : (r.status_label || "Not analysed");
    const td = element("td");
    td.append(element("span", `status status-${r.status || "none"}`, label));
    return td;
  }

  function recentRow(r) {
    const tr = element("tr");
    tr.dataset.recording = r.recording;
    const when = element("td");
    const link = element("a", "", r.uploaded_at);
    link.href = r.url;
    when.append(link);
    tr.append(when);
    if (showPatient) tr.append(element("td", "", r.patient));
    tr.append(element("td", "", r.exercise || "—"), statusCell(r));
    tr.append(element("td", "num score", r.score === null ? "—" : String(r.score)));
    return tr;
  }

  function showRecent(recent) {
    if (!recentRows || recent.length === 0) return;
    recentRows.replaceChildren(...recent.map(recentRow));
  }

  async function poll() {
    let busy = list.children.length > 0;
    if (document.visibilityState === "visible") {
      try {
        const response = await fetch(box.dataset.liveUrl, { headers: { Accept: "application/json" } });
        if (response.ok) {
          const data = await response.json();
          showActive(data.active);
          showRecent(data.recent);
          busy = data.active.length > 0;
          box.dataset.polls = String(Number(box.dataset.polls || 0) + 1);
        }
      } catch (error) { /* network hiccup: try again at the next tick */ }
    }
    setTimeout(poll, busy ? BUSY_MS : IDLE_MS);
  }
  setTimeout(poll, list.children.length > 0 ? BUSY_MS : IDLE_MS);
})();
