// The timeline's layer toggles: each checkbox shows or hides one row of key-pose markers.
(function () {
  document.querySelectorAll(".timeline-layers input[data-layer]").forEach((input) => {
    const rows = document.querySelectorAll(`#timeline .layer[data-layer="${input.dataset.layer}"]`);
    const apply = () => rows.forEach((row) => { row.hidden = !input.checked; });
    input.addEventListener("change", apply);
    apply();
  });
})();
