// The key-pose page: the chosen body part's angle over time (axes in seconds and degrees) beside
// a 3D view of the reference at the pointer's moment (the recording page's viewer, viewer.js),
// key poses added by clicking, selected, moved with ← → and removed with Delete; names typed for
// each kind of key pose are kept and saved. Then live validation of the feedback grammar.
// Data from exercises:tutor-data; saves to exercises:landmarks and exercises:grammar.
import * as THREE from "three";
import { Playback } from "./viewer.js";

const W = 900, H = 320, LEFT = 64, RIGHT = 14, TOP = 26, BOTTOM = 46;
const SHOWN_JOINT = 0xd4772c; // the body part of the curve, in the 3D view

// Round steps for axis ticks: at most `most` ticks over [lo, hi].
function ticks(lo, hi, most, steps) {
  const step = steps.find((s) => (hi - lo) / s <= most) || steps[steps.length - 1];
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9; v += step) out.push(+v.toFixed(6));
  return out;
}

const el = (tag, attrs, text) => {
  const node = document.createElementNS("http://www.w3.org/2000/svg", tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  return node;
};

function keyPosePage(box) {
  const csrf = document.querySelector("[name=csrfmiddlewaretoken]").value;
  const svg = document.getElementById("curves");
  const jointSelect = document.getElementById("joint");
  const kindInput = document.getElementById("ltype");
  const nameInput = document.getElementById("lname");
  let data = null, marks = [], selected = -1, names = {}, cursor = 0, playback = null;
  let lo = 0, hi = 1;

  const seconds = (frame) => frame / data.fps;
  const x = (f) => LEFT + (f / Math.max(1, data.n_frames - 1)) * (W - LEFT - RIGHT);
  const y = (a) => TOP + (1 - (a - lo) / Math.max(1e-9, hi - lo)) * (H - TOP - BOTTOM);
  const frameAt = (px) => Math.max(0, Math.min(data.n_frames - 1,
    Math.round(((px - LEFT) / (W - LEFT - RIGHT)) * (data.n_frames - 1))));
  const kindName = (kind) => names[kind] || (kind === 1 ? "start" : `kind ${kind}`);
  const label = (joint) => data.labels[joint] || "body part";

  // Pointer position in the SVG's own units (the drawing scales with the page).
  function svgX(event) {
    const point = svg.createSVGPoint();
    point.x = event.clientX; point.y = event.clientY;
    return point.matrixTransform(svg.getScreenCTM().inverse()).x;
  }

  function drawAxes(curve) {
    lo = Math.min(...curve); hi = Math.max(...curve);
    const pad = Math.max(2, (hi - lo) * 0.08);
    lo = Math.max(0, Math.floor((lo - pad) / 5) * 5); hi = Math.ceil((hi + pad) / 5) * 5;
    const axis = el("g", { class: "axis" });
    for (const a of ticks(lo, hi, 6, [1, 2, 5, 10, 15, 20, 30, 45, 90])) {
      axis.append(el("line", { x1: LEFT, x2: W - RIGHT, y1: y(a), y2: y(a) }),
        el("text", { x: LEFT - 6, y: y(a) + 4, "text-anchor": "end" }, `${a}°`));
    }
    const duration = seconds(data.n_frames - 1);
    for (const t of ticks(0, duration, 12, [0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300])) {
      const px = x(t * data.fps);
      axis.append(el("line", { x1: px, x2: px, y1: H - BOTTOM, y2: H - BOTTOM + 5 }),
        el("text", { x: px, y: H - BOTTOM + 18, "text-anchor": "middle" }, `${t} s`));
    }
    axis.append(el("line", { x1: LEFT, x2: W - RIGHT, y1: H - BOTTOM, y2: H - BOTTOM, stroke: "#57606a" }),
      el("line", { x1: LEFT, x2: LEFT, y1: TOP, y2: H - BOTTOM, stroke: "#57606a" }),
      el("text", { class: "axis-title", x: (LEFT + W - RIGHT) / 2, y: H - 6, "text-anchor": "middle" }, "Time (seconds)"),
      el("text", { class: "axis-title", x: 14, y: (TOP + H - BOTTOM) / 2, "text-anchor": "middle",
        transform: `rotate(-90 14 ${(TOP + H - BOTTOM) / 2})` }, "Turn from rest (degrees)"),
      el("text", { class: "axis-title", x: LEFT, y: 16 }, `${label(jointSelect.value)}: how far it is turned from its rest position`));
    svg.append(axis);
  }

  function draw() {
    svg.replaceChildren();
    const curve = data.angles_deg[jointSelect.value] || [0];
    drawAxes(curve);
    const points = curve.map((a, f) => `${x(f).toFixed(1)},${y(a).toFixed(1)}`);
    svg.append(el("polyline", { points: points.join(" "), fill: "none", stroke: "#2563eb", "stroke-width": 1.6 }));
    // Suggested key poses: dashed and grey, under the therapist's own marks.
    data.suggested_frames.forEach((frame, i) => {
      svg.append(el("line", { x1: x(frame), x2: x(frame), y1: TOP, y2: H - BOTTOM, stroke: "#9ca3af",
        "stroke-dasharray": "4 3", class: "suggested", "data-type": data.suggested_types[i] }));
    });
    // Names on two rows by kind; a name that would run into the one before it on its row is
    // left out (the selection line below names the selected key pose).
    const rowEnd = [-Infinity, -Infinity];
    marks.forEach((m, i) => {
      svg.append(el("line", { x1: x(m.frame), x2: x(m.frame), y1: TOP, y2: H - BOTTOM,
        stroke: i === selected ? "#dc2626" : "#16a34a", "stroke-width": 3, "data-index": i }));
      const text = kindName(m.type), row = m.type === 1 ? 0 : 1, left = x(m.frame) + 3;
      if (left < rowEnd[row] && i !== selected) return;
      rowEnd[row] = left + text.length * 7 + 8;
      svg.append(el("text", { x: left, y: TOP + 12 + 13 * row, "font-size": 11, class: "mark-name" }, text));
    });
    svg.append(el("line", { id: "cursor", x1: x(cursor), x2: x(cursor), y1: TOP, y2: H - BOTTOM,
      stroke: "#d4772c", "stroke-width": 1 }));
    const s = marks[selected];
    document.getElementById("selection").textContent = s
      ? `Selected: the key pose at ${seconds(s.frame).toFixed(2)} s (${kindName(s.type)}).` : "";
  }

  // The moment shown in 3D: the pointer's, or the selected key pose's.
  function showMoment(frame) {
    cursor = frame;
    const line = document.getElementById("cursor");
    if (line) { line.setAttribute("x1", x(frame)); line.setAttribute("x2", x(frame)); }
    if (playback) playback.setFrame(frame);
    document.getElementById("pose-caption").textContent =
      `The reference at ${seconds(frame).toFixed(2)} s · ${label(jointSelect.value)} in orange`;
  }

  function colourShownJoint() {
    const { joints } = playback.skeletons[0];
    const index = data.joints.indexOf(jointSelect.value);
    if (index < 0 || !joints.instanceColor) return;
    joints.setColorAt(index, new THREE.Color(SHOWN_JOINT));
    joints.instanceColor.needsUpdate = true;
  }

  function select(index) {
    selected = index;
    if (index >= 0) {
      kindInput.value = marks[index].type;
      nameInput.value = names[marks[index].type] || "";
      showMoment(marks[index].frame);
    }
  }

  svg.addEventListener("mousemove", (event) => showMoment(frameAt(svgX(event))));
  svg.addEventListener("click", (event) => {
    const px = svgX(event), hit = marks.findIndex((m) => Math.abs(x(m.frame) - px) < 6);
    if (hit >= 0) { select(hit); } else {
      const type = parseInt(kindInput.value, 10) || 1;
      const name = nameInput.value.trim();
      if (name) names[type] = name;
      marks.push({ frame: frameAt(px), type });
      marks.sort((a, b) => a.frame - b.frame);
      selected = -1;
    }
    svg.focus(); draw();
  });
  svg.addEventListener("keydown", (event) => {
    if (selected < 0) return;
    const step = event.shiftKey ? 10 : 1, m = marks[selected];
    if (event.key === "Delete" || event.key === "Backspace") { marks.splice(selected, 1); selected = -1; }
    else if (event.key === "ArrowLeft") m.frame = Math.max(0, m.frame - step);
    else if (event.key === "ArrowRight") m.frame = Math.min(data.n_frames - 1, m.frame + step);
    else return;
    event.preventDefault();
    if (marks[selected]) showMoment(marks[selected].frame);
    draw();
  });
  // A name typed is kept for its kind at once, whether or not a key pose is added after it.
  nameInput.addEventListener("input", () => {
    const kind = parseInt(kindInput.value, 10) || 1;
    names[kind] = nameInput.value.trim();
    draw();
  });
  kindInput.addEventListener("input", () => {
    nameInput.value = names[parseInt(kindInput.value, 10) || 1] || "";
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
    document.getElementById("landmarks-status").textContent = answer.ok ? (body.message || "Saved.")
      : Object.values(body.errors || {}).flat().map((e) => e.message).join(" ");
  }

  function startViewer() {
    const meta = { frames: data.n_frames, joints: data.joints.length, fps: data.fps, names: data.joints,
      parents: data.pose.parents, skeletons: [{ key: "tutor" }], assessment: [] };
    playback = new Playback(document.getElementById("pose-view"), meta, Float32Array.from(data.pose.positions));
    playback.onFrame(colourShownJoint);
  }

  function fillJoints() {
    const joints = document.getElementById("joints");
    for (const name of data.movement_order) jointSelect.append(new Option(label(name), name));
    jointSelect.selectedIndex = 0; // the body part that moves most
    for (const name of data.body_parts || data.joints) { // each body part once
      const row = document.createElement("label");
      const tick = Object.assign(document.createElement("input"), { type: "checkbox", value: name,
        checked: data.involved_joints.includes(name) });
      row.append(tick, document.createTextNode(label(name)));
      joints.append(row);
    }
  }

  async function load() {
    data = await (await fetch(box.dataset.tutorUrl)).json();
    names = Object.fromEntries(Object.entries(data.type_names || {}).filter(([, v]) => v));
    marks = data.landmark_frames.map((frame, i) => ({ frame, type: data.landmark_types[i] }));
    nameInput.value = names[1] || "";
    fillJoints();
    jointSelect.addEventListener("change", () => { draw(); showMoment(cursor); });
    document.getElementById("save-landmarks").addEventListener("click", save);
    const accept = document.getElementById("use-suggestions");
    accept.disabled = data.suggested_frames.length === 0;
    accept.addEventListener("click", () => {
      marks = data.suggested_frames.map((frame, i) => ({ frame, type: data.suggested_types[i] }));
      names = { 1: names[1] || "start", 2: names[2] || "far end of the movement", ...names };
      nameInput.value = names[parseInt(kindInput.value, 10) || 1] || "";
      selected = -1; draw();
    });
    draw();
    try { startViewer(); } catch (error) { document.getElementById("pose-caption").textContent = "3D view unavailable in this browser."; }
    showMoment(marks.length ? marks[0].frame : 0);
    box.dataset.ready = "1";
    window.keyPosePage = { get playback() { return playback; }, get cursor() { return cursor; }, get names() { return names; } };
  }
  load();
}

function grammarEditor(editor) {
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
}

const box = document.getElementById("annotate");
if (box) keyPosePage(box);
const editor = document.getElementById("grammar-editor");
if (editor) grammarEditor(editor);
