// Tutor key-pose annotation (click to add, select + arrows to move, Delete to remove) and live
// validation of the feedback grammar. Data from exercises:tutor-data; saves to exercises:landmarks.
(function () {
  const box = document.getElementById("annotate");
  if (!box) return;
  const csrf = document.querySelector("[name=csrfmiddlewaretoken]").value;
  const svg = document.getElementById("curves");
  const W = 900, H = 260, PAD = 30;
  let data = null, marks = [], selected = -1, names = {};

  const x = (f) => PAD + (f / Math.max(1, data.n_frames - 1)) * (W - 2 * PAD);
  const frameAt = (px) => Math.round(((px - PAD) / (W - 2 * PAD)) * (data.n_frames - 1));
  const el = (tag, attrs) => {
    const node = document.createElementNS("http://www.w3.org/2000/svg", tag);
    for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
    return node;
  };

  function draw() {
    svg.replaceChildren();
    const curve = data.angles_deg[document.getElementById("joint").value] || [];
    const top = Math.max(1, ...curve);
    const points = curve.map((a, f) => `${x(f)},${H - PAD - (a / top) * (H - 2 * PAD)}`);
    svg.append(el("polyline", { points: points.join(" "), fill: "none", stroke: "#2563eb" }));
    // Suggested key poses: dashed and grey, under the therapist's own marks.
    data.suggested_frames.forEach((frame, i) => {
      svg.append(el("line", { x1: x(frame), x2: x(frame), y1: PAD, y2: H - PAD, stroke: "#9ca3af",
        "stroke-dasharray": "4 3", class: "suggested", "data-type": data.suggested_types[i] }));
    });
    marks.forEach((m, i) => {
      const line = el("line", { x1: x(m.frame), x2: x(m.frame), y1: PAD, y2: H - PAD,
        stroke: i === selected ? "#dc2626" : "#16a34a", "stroke-width": 3, "data-index": i });
      const label = el("text", { x: x(m.frame) + 3, y: PAD - 6, "font-size": 11 });
      label.textContent = `${m.type}`;
      svg.append(line, label);
    });
    const s = marks[selected];
    document.getElementById("selection").textContent = s
      ? `Selected: frame ${s.frame}, type ${s.type} (${names[s.type] || "unnamed"})` : "";
  }

  svg.addEventListener("click", (event) => {
    const px = event.offsetX, hit = marks.findIndex((m) => Math.abs(x(m.frame) - px) < 5);
    if (hit >= 0) { selected = hit; } else {
      const type = parseInt(document.getElementById("ltype").value, 10) || 1;
      const name = document.getElementById("lname").value.trim();
      if (name) names[type] = name;
      marks.push({ frame: Math.max(0, Math.min(data.n_frames - 1, frameAt(px))), type });
      marks.sort((a, b) => a.frame - b.frame);
      selected = -1;
    }
    svg.focus(); draw();
  });
  svg.addEventListener("keydown", (event) => {
    if (selected < 0) return;
    const step = event.shiftKey ? 10 : 1;
    if (event.key === "Delete" || event.key === "Backspace") { marks.splice(selected, 1); selected = -1; }
    else if (event.key === "ArrowLeft") marks[selected].frame = Math.max(0, marks[selected].frame - step);
    else if (event.key === "ArrowRight") marks[selected].frame = Math.min(data.n_frames - 1, marks[selected].frame + step);
    else return;
    event.preventDefault(); draw();
  });

  async function save() {
    const chosen = [...document.querySelectorAll("#joints input:checked")].map((c) => c.value);
    const form = new FormData();
    form.append("frames", marks.map((m) => m.frame).join(";"));
    form.append("types", marks.map((m) => m.type).join(";"));
    form.append("type_names", JSON.stringify(names));
    form.append("involved_joints", JSON.stringify(chosen));
    const answer = await fetch(box.dataset.saveUrl, { method: "POST", body: form, headers: { "X-CSRFToken": csrf } });
    const body = await answer.json();
    document.getElementById("landmarks-status").textContent = answer.ok ? "Saved."
      : Object.values(body.errors || {}).flat().map((e) => e.message).join(" ");
  }

  async function load() {
    data = await (await fetch(box.dataset.tutorUrl)).json();
    names = { ...data.type_names };
    marks = data.landmark_frames.map((frame, i) => ({ frame, type: data.landmark_types[i] }));
    const select = document.getElementById("joint"), joints = document.getElementById("joints");
    for (const name of data.joints) {
      select.append(new Option(name, name));
      const label = document.createElement("label");
      const box_ = Object.assign(document.createElement("input"), { type: "checkbox", value: name,
        checked: data.involved_joints.includes(name) });
      label.append(box_, " " + name); joints.append(label);
    }
    select.addEventListener("change", draw);
    document.getElementById("save-landmarks").addEventListener("click", save);
    const accept = document.getElementById("use-suggestions");
    accept.disabled = data.suggested_frames.length === 0;
    accept.addEventListener("click", () => {
      marks = data.suggested_frames.map((frame, i) => ({ frame, type: data.suggested_types[i] }));
      names = { 1: names[1] || "rest", 2: names[2] || "extreme", ...names };
      selected = -1; draw();
    });
    draw();
  }
  load();
})();

(function () {
  const editor = document.getElementById("grammar-editor");
  if (!editor) return;
  const csrf = document.querySelector("[name=csrfmiddlewaretoken]").value;
  const text = document.getElementById("grammar"), status = document.getElementById("grammar-status");
  let timer = null;
  async function check(save) {
    const answer = await fetch(editor.dataset.checkUrl, { method: "POST",
      headers: { "Content-Type": "application/json", "X-CSRFToken": csrf },
      body: JSON.stringify({ text: text.value, save }) });
    const body = await answer.json();
    status.className = body.valid ? "ok" : "error";
    status.textContent = body.valid ? (body.saved ? "Saved." : `Valid: ${body.rules} rules.`)
      : `Line ${body.line}, column ${body.column}: ${body.message}`;
  }
  text.addEventListener("input", () => { clearTimeout(timer); timer = setTimeout(() => check(false), 400); });
  document.getElementById("save-grammar").addEventListener("click", () => check(true));
  if (text.value) check(false);
})();
