// The live page: follows a live session's WebSocket, draws the patient and the tutor (kept in
// step by the server's forward-plotting aligner) with the recording page's viewer, counts
// repetitions, shows (and optionally speaks) guidance, and the live beside the offline figures.
import { Playback } from "./viewer.js";

const $ = (id) => document.getElementById(id);
const root = $("live");
let viewer = null;
let errors = 0;
const rows = new Map();

function pose(event) {
  const n = event.parents.length;
  if (!viewer) {
    const meta = {
      frames: 1, joints: n, fps: 30, parents: event.parents, names: event.parents.map(String),
      skeletons: [{ key: "patient", label: "patient" }, { key: "tutor", label: "tutor" }],
    };
    const first = new Float32Array(2 * n * 3);
    first.set(event.patient, 0);
    first.set(event.tutor, n * 3);
    viewer = new Playback(root, meta, first); // the camera fits the first poses
    viewer.sideBySide = true;
    viewer.visible = [true, true];
  }
  viewer.positions.set(event.patient, 0);
  viewer.positions.set(event.tutor, n * 3);
  viewer.setFrame(0);
}

function say(text) {
  if (!text) return;
  $("guidance").textContent = text;
  if ($("speak").checked && "speechSynthesis" in window) {
    window.speechSynthesis.speak(new SpeechSynthesisUtterance(text));
  }
}

function repetition(event) {
  // the server's words: praise only for a passed repetition, a failed one is told why
  const tips = event.guidance.map((g) => g.type).join(", ") || "–";
  const verdict = event.passed ? "passed" : "not passed";
  const tr = document.createElement("tr");
  tr.innerHTML = `<td>${event.index + 1}</td><td>${event.start}–${event.end}</td>` +
    `<td>${event.score.toFixed(1)} (${verdict})</td><td>${tips}</td><td class="offline">…</td>`;
  tr.dataset.words = event.words; // what was said, for this repetition
  $("reps").append(tr);
  rows.set(event.index, tr);
  $("rep-count").textContent = event.index + 1;
  say(event.words);
}

function position(event) {
  $("live-state").textContent = "Live";
  if (event.patient) pose(event);
}

function summary(event) {
  $("live-state").textContent = "Ended";
  $("rep-count").textContent = event.repetitions;
  $("summary").textContent = `Live: ${event.repetitions} repetitions` +
    (event.dropped ? `; ${event.dropped} movements arrived too fast and were left out` : "");
  pollOffline();
}

async function pollOffline() {
  const body = await fetch(root.dataset.statusUrl).then((r) => r.json());
  const offline = body.offline;
  if (!offline) return;
  if (offline.status !== "succeeded") {
    $("offline").textContent = `Analysis of the recording: ${offline.status} (${offline.progress} %)`;
    if (offline.status !== "failed") setTimeout(pollOffline, 2000);
    return;
  }
  $("offline").innerHTML = `Analysis of the recording: ${offline.repetitions.length} repetitions, score ` +
    `${offline.score ?? "–"} (<a href="${root.dataset.recordingBase}${body.recording}/">recording</a>)`;
  // A session that ended before this page opened has no live rows: the analysis lists them.
  const listed = rows.size > 0;
  offline.repetitions.forEach((rep, i) => {
    let tr = rows.get(i);
    if (!tr && !listed) {
      tr = document.createElement("tr");
      tr.innerHTML = `<td>${i + 1}</td><td>${rep.start}–${rep.end}</td><td>–</td><td>–</td><td class="offline"></td>`;
      $("reps").append(tr);
      rows.set(i, tr);
    }
    if (tr) tr.querySelector(".offline").textContent = rep.score == null ? "–" : rep.score.toFixed(1);
  });
}

const HANDLERS = { position, repetition, summary, ready: () => {},
  error: showError };

// The session's reason for refusing or dropping frames, in the therapist's words (the model
// not built yet, a skeleton that does not fit): shown, not only counted.
function showError(event) {
  errors += 1;
  $("errors").textContent = errors;
  if (event.message) {
    $("live-error").textContent = event.message;
    $("live-error").hidden = false;
  }
}

function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  const socket = new WebSocket(`${scheme}://${location.host}${root.dataset.ws}`);
  socket.onmessage = (message) => {
    const event = JSON.parse(message.data);
    (HANDLERS[event.event] || (() => {}))(event);
  };
  socket.onclose = (e) => { if (e.code !== 4403 && $("live-state").textContent !== "Ended") setTimeout(connect, 1000); };
}

connect();
