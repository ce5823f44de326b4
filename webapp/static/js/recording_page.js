// The recording page: loads the playback payload, drives the 3D viewer, the timeline with
// repetitions, key poses and feedback captions, and the Plotly charts linked to playback.
import { Playback, SKELETON_COLOURS } from "./viewer.js";
import { linkVideo } from "./video_sync.js";

// Paper 001's guidance types in the words the therapist reads (as webapp/reports/timeline.py).
const GUIDANCE_WORDS = { "too fast": "too fast", "too slow": "too slow", overdone: "went too far", incomplete: "did not reach far enough" };
const guidanceWords = (type) => GUIDANCE_WORDS[type] ?? String(type).replaceAll("_", " ");
// Body parts and skeletons come named in plain words by the server (webapp.recordings.words):
// series carry `label` ("left thigh") and `skeleton_label` ("the reference adjusted to your level").
const hex = (n) => "#" + n.toString(16).padStart(6, "0");
const $ = (id) => document.getElementById(id);

async function load(root) {
  const [meta, buffer] = await Promise.all([
    fetch(root.dataset.playback).then((r) => r.json()),
    fetch(root.dataset.positions).then((r) => (r.ok ? r.arrayBuffer() : null)),
  ]);
  if (!meta.available || !buffer) {
    root.querySelector(".viewer-stage").textContent = meta.message || "No playback data.";
    return null;
  }
  return { meta, positions: new Float32Array(buffer) };
}

function addToggles(playback) {
  const box = $("skeleton-toggles");
  playback.meta.skeletons.forEach((skeleton, s) => {
    const label = document.createElement("label");
    label.style.color = hex(SKELETON_COLOURS[skeleton.key] ?? 0x888888);
    label.innerHTML = `<input type="checkbox" data-skeleton="${s}"> ${skeleton.label}`;
    const input = label.querySelector("input");
    input.checked = playback.visible[s];
    input.addEventListener("change", () => { playback.visible[s] = input.checked; playback.setFrame(playback.frame); });
    box.append(label, " ");
  });
}

function addControls(playback) {
  const play = $("play");
  const setPlaying = (on) => { playback.playing = on; play.textContent = on ? "Pause" : "Play"; };
  play.addEventListener("click", () => setPlaying(!playback.playing));
  // Started or stopped elsewhere too (the video's own controls, the end of the video).
  playback.onPlaying((on) => { play.textContent = on ? "Pause" : "Play"; });
  $("step-back").addEventListener("click", () => { setPlaying(false); playback.setFrame(playback.frame - 1); });
  $("step-fwd").addEventListener("click", () => { setPlaying(false); playback.setFrame(playback.frame + 1); });
  $("speed").addEventListener("change", (e) => { playback.speed = Number(e.target.value); });
  $("side-by-side").addEventListener("change", (e) => { playback.sideBySide = e.target.checked; playback.setFrame(playback.frame); });
  const loop = $("loop");
  const secs = (f) => (f / playback.meta.fps).toFixed(1);
  playback.meta.repetitions.forEach((rep, i) => loop.add(new Option(`#${i + 1} (${secs(rep.start)}–${secs(rep.end)} s)`, i)));
  loop.addEventListener("change", () => {
    const rep = playback.meta.repetitions[loop.value];
    playback.loop = rep ? [rep.start, rep.end] : null;
    if (rep) playback.setFrame(rep.start);
  });
  $("replay-key").addEventListener("click", () => {
    const before = playback.meta.landmarks.filter((m) => m.frame <= playback.frame);
    const last = before.length ? before[before.length - 1] : playback.meta.landmarks[0];
    playback.setFrame(last ? last.frame : 0);
    setPlaying(true);
  });
  const scrub = $("scrub");
  scrub.max = playback.nFrames - 1;
  scrub.addEventListener("input", () => playback.setFrame(Number(scrub.value)));
  return setPlaying;
}

function addTimeline(playback) {
  // Repetitions, guidance and the key-pose layers are drawn by the server (timeline.html);
  // here every marker jumps to its frame, and a click elsewhere seeks.
  const line = $("timeline");
  const at = (frame) => `${(100 * frame) / Math.max(1, playback.nFrames - 1)}%`;
  line.querySelectorAll("[data-frame]").forEach((mark) => {
    mark.addEventListener("click", (e) => {
      e.stopPropagation();
      playback.playing = false;
      $("play").textContent = "Play";
      playback.setFrame(Number(mark.dataset.frame));
    });
  });
  const cursor = document.createElement("div");
  cursor.id = "timeline-cursor";
  Object.assign(cursor.style, { position: "absolute", top: 0, bottom: 0, width: "2px", background: "#cf222e", left: "0%", pointerEvents: "none" });
  line.append(cursor);
  line.addEventListener("click", (e) => {
    if (e.target.closest("[data-frame]")) return;
    const box = line.getBoundingClientRect();
    playback.setFrame(((e.clientX - box.left) / box.width) * (playback.nFrames - 1));
  });
  return (frame) => { cursor.style.left = at(frame); };
}

function captions(playback) {
  const caption = $("caption");
  const spoken = new Set();
  let previous = -1;
  return (frame) => {
    for (const item of playback.meta.feedback) {
      const crossed = playback.playing && item.frame > previous && item.frame <= frame;
      if (!crossed && item.frame !== frame) continue;
      caption.textContent = item.text;
      const tip = item.tip || item.text;
      if (crossed && $("speak").checked && !spoken.has(tip) && window.speechSynthesis) {
        spoken.add(tip);  // each tip once
        window.speechSynthesis.speak(new SpeechSynthesisUtterance(tip));
      }
    }
    previous = frame;
  };
}

// The clinical angles of the table beside the chart, frame by frame (webapp.reports.playback):
// each named with its normal adult range; those of the body parts the exercise moves shown.
function angleTraces(meta, seconds) {
  const x = meta.angles.frames.map(seconds);
  const anyInvolved = meta.angles.series.some((s) => s.involved);
  return meta.angles.series.map((s, i) => ({
    x, y: s.values, mode: "lines", connectgaps: false,
    name: window.legendName(s.normal ? `${s.label} (normal ${s.normal[0]}° to ${s.normal[1]}°)` : s.label),
    visible: (anyInvolved ? s.involved : i < 3) ? true : "legendonly",
  }));
}

// Angles between body segments (180° is straight): never clinical angles, so under their own name.
function segmentTraces(meta, seconds) {
  const x = meta.segments.frames.map(seconds);
  const joints = [...new Set(meta.segments.series.map((s) => s.joint))];
  return meta.segments.series.map((s) => ({
    x, y: s.values, name: window.legendName(`${s.label} · ${s.skeleton_label ?? s.skeleton}`), mode: "lines",
    line: { dash: s.skeleton === "patient" ? "solid" : "dot" },
    visible: joints.indexOf(s.joint) < 3 ? true : "legendonly",
  }));
}

// For a therapist who asks for them, in a chart of their own.
function segmentChart(meta, seconds, layout) {
  const box = $("show-segments");
  if (!box) return;
  box.addEventListener("change", () => {
    $("segments").hidden = !box.checked;
    if (box.checked) Plotly.newPlot($("chart-segments"), segmentTraces(meta, seconds), layout, window.chartConfig());
  });
}

// A run analysed before the clinical curves were kept has only the segments' angles: the chart
// shows them under their own name, never as joint angles.
function segmentsInstead() {
  $("angles-title").textContent = "Angles between body segments (degrees, over time in seconds)";
  $("angles-help").textContent = "Not the clinical angles of the table below (this recording was analysed before their curves were kept): the angle between each body segment and the next, 180° being a straight line.";
  if ($("segments-choice")) $("segments-choice").hidden = true;
}

function charts(playback) {
  if (!window.Plotly) return () => {};
  const { meta } = playback;
  const seconds = (f) => f / meta.fps;
  const clinical = angleTraces(meta, seconds);
  const traces = clinical.length ? clinical : segmentTraces(meta, seconds);
  const marks = meta.landmarks.map((m) => ({ type: "line", xref: "x", yref: "paper", x0: seconds(m.frame), x1: seconds(m.frame), y0: 0, y1: 1, line: { color: "#bbb", width: 1, dash: "dot" } }));
  const layout = { margin: { t: 10, r: 10, b: 40, l: 45 }, xaxis: { title: { text: "time (s)" } }, yaxis: { title: { text: "angle (°)" } }, shapes: marks, legend: window.legendAbove() };
  const chart = $("chart-angles");
  segmentChart(meta, seconds, layout);
  const reps = meta.repetitions;
  Plotly.newPlot($("chart-reps"), [{ type: "bar", x: reps.map((_, i) => `#${i + 1}`), y: reps.map((r) => r.score), text: reps.map((r) => (r.guidance || []).map((g) => guidanceWords(g.type)).join(", ")), marker: { color: "#1f6feb" } }], { margin: { t: 10, r: 10, b: 40, l: 50 }, xaxis: { title: { text: "repetition (number)" }, type: "category" }, yaxis: { range: [0, 100], title: { text: "score (0–100)" } } }, window.chartConfig());
  if (!clinical.length) segmentsInstead();
  Plotly.newPlot(chart, traces, layout, window.chartConfig());
  chart.on("plotly_click", (e) => { playback.playing = false; $("play").textContent = "Play"; playback.setFrame(e.points[0].x * meta.fps); });
  // The time cursor is a positioned overlay, not a Plotly shape: relayout is too slow to run
  // at the animation rate.
  const cursor = document.createElement("div");
  cursor.id = "chart-cursor";
  Object.assign(cursor.style, { position: "absolute", width: "2px", background: "#cf222e", pointerEvents: "none" });
  chart.style.position = "relative";
  chart.append(cursor);
  return (frame) => {
    const full = chart._fullLayout;
    if (!full || !full.xaxis) return;
    // _size: the plot area as drawn, after Plotly grew the margins for the legend and ticks
    // (`margin` holds only the margins asked for)
    cursor.style.left = `${full._size.l + full.xaxis.l2p(seconds(frame))}px`;
    cursor.style.top = `${full._size.t}px`;
    cursor.style.height = `${full._size.h}px`;
  };
}

async function main() {
  const root = $("viewer");
  if (!root) return;
  const data = await load(root);
  if (!data) return;
  const playback = new Playback(root, data.meta, data.positions);
  window.physioPlayback = playback;  // for the browser tests and measurements
  const video = $("recording-video");
  if (video) linkVideo(playback, video);
  addToggles(playback);
  addControls(playback);
  const moveCursor = addTimeline(playback);
  const showCaption = captions(playback);
  const moveChartCursor = charts(playback);
  const label = $("frame-label");
  const scrub = $("scrub");
  playback.onFrame((frame) => {
    label.textContent = `${(frame / data.meta.fps).toFixed(2)} s`;
    scrub.value = frame;
    moveCursor(frame);
    showCaption(frame);
    moveChartCursor(frame);
  });
  playback.setFrame(0);
  root.dataset.readyAt = performance.now().toFixed(0);  // ms since navigation start
  root.dataset.ready = "1";
}

main();
