// The camera page: the camera's picture with the body found in it drawn over it, the
// demonstration kept in step beside it, the count, and each repetition's words (shown and spoken).
// The pose engine (camera_pose.js) runs here, in the browser; only the landmarks go to the live
// session, as binary frames (analysis/live/frames.py: "LVF", version 1, float32 values), resampled
// to the session's steady frame rate. The pictures never leave the device.
import { createPoseEngine } from "./camera_pose.js";

const $ = (id) => document.getElementById(id);
const root = $("camera");
const FPS = Number(root.dataset.fps);
const VALUES = 33 * 4;
// BlazePose landmarks every frame must show for the exercise's skeleton: head (ears), shoulders,
// elbows, wrists, hips, knees, ankles (the server fits the skeleton to these).
const NEEDED = [7, 8, 11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28];
const BONES = [[11, 12], [11, 13], [13, 15], [12, 14], [14, 16], [11, 23], [12, 24], [23, 24],
  [23, 25], [25, 27], [24, 26], [26, 28], [27, 31], [28, 32], [7, 8]];
const MESSAGES = {
  refused: "The camera was refused. Allow this site to use the camera (the camera icon in the address bar), then press Start again.",
  absent: "No camera was found. Connect a camera, or open this page on a phone or laptop with one.",
  nobody: "No one is in view: stand in front of the camera, about two to three metres away.",
  close: "You are too close to the camera: step back until your whole body, from head to feet, is in the picture.",
  ended: "The session has ended and is saved with your recordings.",
};

const state = { socket: null, engine: null, stream: null, paused: false, seq: 0,
  previous: null, nextTick: null, count: 0, ended: false };

function setState(value) {
  const el = $("camera-state");
  el.dataset.liveState = value;
  el.textContent = value === "running" ? (state.paused ? "paused" : "running") : value;
}

function message(key, text) {
  $("camera-message").textContent = text || MESSAGES[key] || "";
  $("camera-message").dataset.reason = key || "";
}

function setCount(n) {
  state.count = n;
  document.querySelector("[data-live-count]").textContent = String(n);
}

function say(text) {
  if (!text) return;
  $("camera-words").textContent = text;
  if ($("camera-speak").checked && "speechSynthesis" in window) {
    window.speechSynthesis.speak(new SpeechSynthesisUtterance(text));
  }
}

// ---- the session -------------------------------------------------------------------------

function encode(seq, frames) {
  const buffer = new ArrayBuffer(12 + 4 * VALUES * frames.length);
  const view = new DataView(buffer);
  [76, 86, 70, 1].forEach((b, i) => view.setUint8(i, b)); // "LVF", version 1
  view.setUint16(4, frames.length, true);
  view.setUint16(6, VALUES, true);
  view.setUint32(8, seq, true);
  frames.forEach((frame, f) => frame.forEach((v, k) => view.setFloat32(12 + 4 * (f * VALUES + k), v, true)));
  return buffer;
}

function send(frames) {
  const socket = state.socket;
  if (!frames.length || !socket || socket.readyState !== WebSocket.OPEN) return;
  for (let i = 0; i < frames.length; i += 64) {
    const part = frames.slice(i, i + 64);
    socket.send(encode(state.seq, part));
    state.seq += part.length;
  }
}

// Frames at the session's steady rate, interpolated between the engine's results (which come as
// fast as the device finds bodies): the session reads time from the frame count.
function resample(time, world) {
  const step = 1000 / FPS;
  const out = [];
  if (state.previous === null) {
    out.push(world);
    state.nextTick = time + step;
  } else {
    const [t0, w0] = state.previous;
    for (; state.nextTick <= time; state.nextTick += step) {
      const a = time > t0 ? (state.nextTick - t0) / (time - t0) : 1;
      out.push(w0.map((v, k) => (k % 4 === 3 ? Math.min(v, world[k]) : v + a * (world[k] - v))));
    }
  }
  state.previous = [time, world];
  return out;
}

const HANDLERS = {
  ready: () => {},
  position: (event) => { if (event.tutor) drawDemonstration(event.tutor, event.parents); },
  repetition: (event) => {
    setCount(Math.max(state.count, event.index + 1));
    const item = document.createElement("li");
    item.textContent = event.words || "";
    $("camera-reps").append(item);
    say(event.words);
  },
  summary: (event) => {
    state.ended = true;
    setCount(event.repetitions);
    setState("ended");
    message("ended");
    const link = event.recording ? ` <a href="${root.dataset.recordingBase}${event.recording}/">See this session</a>` : "";
    $("camera-summary").innerHTML = `${event.repetitions} repetitions.${link}`;
    if (state.socket) state.socket.close();
  },
  error: (event) => {
    if (event.code === "not-in-view" || event.code === "camera-frame" || event.code === "rate-limit") return;
    message("error", event.message);
  },
};

function connect(ws) {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  const socket = new WebSocket(`${scheme}://${location.host}${ws}`);
  socket.binaryType = "arraybuffer";
  socket.onopen = () => socket.send(JSON.stringify({ type: "start", source: "camera", fps: FPS }));
  socket.onmessage = (m) => {
    const body = JSON.parse(m.data);
    (Array.isArray(body) ? body : [body]).forEach((e) => (HANDLERS[e.event] || (() => {}))(e));
  };
  socket.onclose = (e) => {
    if (!state.ended && e.code !== 4403) setTimeout(() => { state.socket = connect(ws); }, 1000);
  };
  return socket;
}

// ---- drawing -----------------------------------------------------------------------------

function drawBody(image) {
  const canvas = $("camera-overlay");
  const video = $("camera-video");
  canvas.width = video.videoWidth || 640;
  canvas.height = video.videoHeight || 480;
  const g = canvas.getContext("2d");
  g.clearRect(0, 0, canvas.width, canvas.height);
  if (!image) return;
  g.lineWidth = Math.max(3, canvas.width / 120);
  g.strokeStyle = "#2ea043";
  const at = (p) => [p.x * canvas.width, p.y * canvas.height];
  for (const [a, b] of BONES) {
    if (image[a].visibility < 0.5 || image[b].visibility < 0.5) continue;
    g.beginPath(); g.moveTo(...at(image[a])); g.lineTo(...at(image[b])); g.stroke();
  }
}

function drawDemonstration(flat, parents) {
  const canvas = $("camera-demo");
  const g = canvas.getContext("2d");
  const n = parents.length;
  const turn = 0.6; // radians: a three-quarter view shows bending both ways
  const pts = [];
  for (let j = 0; j < n; j++) {
    const [x, y, z] = [flat[3 * j], flat[3 * j + 1], flat[3 * j + 2]];
    pts.push([x * Math.cos(turn) + z * Math.sin(turn), y]);
  }
  const ys = pts.map((p) => p[1]);
  const top = Math.max(...ys);
  const scale = (canvas.height * 0.85) / Math.max(1, top - Math.min(...ys, 0));
  g.clearRect(0, 0, canvas.width, canvas.height);
  g.lineWidth = 6; g.strokeStyle = "#8250df"; g.lineCap = "round";
  const at = (p) => [canvas.width / 2 + p[0] * scale, canvas.height * 0.07 + (top - p[1]) * scale];
  parents.forEach((p, j) => {
    if (p < 0) return;
    g.beginPath(); g.moveTo(...at(pts[p])); g.lineTo(...at(pts[j])); g.stroke();
  });
}

// ---- the camera ----------------------------------------------------------------------------

// In the picture: a landmark MediaPipe places outside it is a guess. One hidden behind the body
// (the far arm in a side view) is inside it and counts as seen, as the video upload reads it.
function inPicture(p) {
  return p.x >= 0 && p.x <= 1 && p.y >= 0 && p.y <= 1;
}

function inView(image) {
  return NEEDED.every((k) => inPicture(image[k]));
}

// The landmarks sent: a landmark outside the picture gets visibility 0 (the session keeps its
// last position), every other 1.
function seen(world, image) {
  const out = Array.from(world);
  image.forEach((p, k) => { out[4 * k + 3] = inPicture(p) ? 1 : 0; });
  return out;
}

function onResult({ time, world, image }) {
  drawBody(image);
  if (state.ended) return;
  if (!world) { message("nobody"); state.previous = null; return; }
  if (!inView(image)) { message("close"); state.previous = null; return; }
  if ($("camera-message").dataset.reason !== "error") message("");
  if (!state.paused) send(resample(time, seen(world, image)));
}

async function openCamera() {
  if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) throw Object.assign(new Error("absent"), { name: "NotFoundError" });
  const stream = await navigator.mediaDevices.getUserMedia({ audio: false,
    video: { facingMode: "user", width: { ideal: 640 }, height: { ideal: 480 } } });
  const video = $("camera-video");
  video.srcObject = stream;
  await video.play();
  return stream;
}

function csrf() {
  return document.querySelector("input[name=csrfmiddlewaretoken]").value;
}

async function start() {
  $("camera-start").disabled = true;
  message("", "Opening the camera…");
  try {
    state.stream = await openCamera();
  } catch (error) {
    const refused = ["NotAllowedError", "SecurityError", "PermissionDeniedError"].includes(error.name);
    message(refused ? "refused" : "absent");
    $("camera-start").disabled = false;
    return;
  }
  message("", "Getting ready to find you in the picture…");
  const answer = await fetch(root.dataset.startUrl, { method: "POST", headers: { "X-CSRFToken": csrf() } });
  const body = await answer.json();
  if (!answer.ok) { message("error", body.error); return; }
  state.engine = state.engine || await createPoseEngine({ base: root.dataset.poseBase, onResult });
  window.cameraEngine = state.engine; // the page's figures (frames a second) for the benchmark
  state.socket = connect(body.ws);
  state.engine.start($("camera-video"));
  setState("running");
  $("camera-pause").disabled = false;
  $("camera-stop").disabled = false;
}

function pause() {
  state.paused = !state.paused;
  state.previous = null; // the pause is not filled with frames
  $("camera-pause").textContent = state.paused ? "Resume" : "Pause";
  setState("running");
}

function stop() {
  $("camera-pause").disabled = true;
  $("camera-stop").disabled = true;
  if (state.engine) state.engine.stop();
  if (state.stream) state.stream.getTracks().forEach((t) => t.stop());
  if (state.socket && state.socket.readyState === WebSocket.OPEN) {
    state.socket.send(JSON.stringify({ type: "end" }));
    message("", "Saving the session…");
  } else {
    state.ended = true;
    setState("ended");
  }
}

if ($("camera-start")) {
  $("camera-start").addEventListener("click", start);
  $("camera-pause").addEventListener("click", pause);
  $("camera-stop").addEventListener("click", stop);
}
