// The compare page: the playbacks of two recordings side by side, driven by one play button and
// one slider. Each viewer is the recording page's Playback (viewer.js); it never plays on its own:
// this module moves both to the frames that match one shared position, so they stay in step.
//
// The shared position is, by repetition, "repetition k and a fraction u through it" (0..K, K the
// repetitions both recordings have), or, by time, the fraction of each recording played (0..1).
import { Playback } from "./viewer.js";

const STEPS = 1000; // the slider's resolution over the whole shared span

async function loadViewer(root) {
  const [meta, buffer] = await Promise.all([
    fetch(root.dataset.playback).then((r) => r.json()),
    fetch(root.dataset.positions).then((r) => (r.ok ? r.arrayBuffer() : null)),
  ]);
  if (!meta.available || !buffer) {
    root.querySelector(".viewer-stage").textContent = meta.message || "No playback for this recording.";
    return null;
  }
  const playback = new Playback(root, meta, new Float32Array(buffer));
  playback.visible = meta.skeletons.map((_, i) => i === 0); // the recorded movement only
  return playback;
}

// Repetition k (clamped) and the fraction through it, for a shared position.
function repetitionAt(position, count) {
  const k = Math.min(Math.floor(position), count - 1);
  return { k, u: Math.min(1, position - k) };
}

function frameAt(meta, mode, position, count) {
  if (mode !== "repetition") return position * (meta.frames - 1);
  const { k, u } = repetitionAt(position, count);
  const rep = meta.repetitions[k];
  return rep.start + u * (rep.end - rep.start);
}

// Seconds one unit of position lasts: the longer recording's, so neither plays faster than it was
// recorded and the shorter one is slowed down to stay in step.
function secondsPerUnit(metas, mode, position, count) {
  if (mode !== "repetition") return Math.max(...metas.map((m) => m.frames / m.fps));
  const { k } = repetitionAt(position, count);
  return Math.max(...metas.map((m) => (m.repetitions[k].end - m.repetitions[k].start + 1) / m.fps));
}

function clockText(meta, frame) {
  const index = meta.repetitions.findIndex((rep) => rep.start <= frame && frame <= rep.end);
  const time = `${(frame / meta.fps).toFixed(2)} s`;
  const rep = index >= 0 ? `repetition ${index + 1} of ${meta.repetitions.length}` : "";
  return [time, rep];
}

class InStep {
  constructor(playbacks, roots) {
    this.playbacks = playbacks;
    this.roots = roots;
    const metas = playbacks.map((p) => p.meta);
    this.metas = metas;
    this.count = Math.min(...metas.map((m) => m.repetitions.length));
    this.mode = this.count > 0 ? "repetition" : "time";
    this.position = 0;
    this.playing = false;
    this.last = performance.now();
  }

  span() { return this.mode === "repetition" ? this.count : 1; }

  seek(position) {
    const span = this.span();
    this.position = Math.max(0, Math.min(span, position));
    this.playbacks.forEach((playback, i) => {
      playback.setFrame(frameAt(playback.meta, this.mode, this.position, this.count));
      const [time, rep] = clockText(playback.meta, playback.frame);
      this.roots[i].querySelector(".time-label").textContent = time;
      this.roots[i].querySelector(".rep-label").textContent = rep;
    });
    document.getElementById("compare-scrub").value = Math.round((this.position / span) * STEPS);
  }

  tick(now) {
    const elapsed = (now - this.last) / 1000;
    this.last = now;
    if (this.playing) {
      const next = this.position + elapsed / secondsPerUnit(this.metas, this.mode, this.position, this.count);
      this.seek(next >= this.span() ? 0 : next); // from the start again, as the recording page loops
    }
    requestAnimationFrame((t) => this.tick(t));
  }
}

function wireControls(inStep) {
  const play = document.getElementById("compare-play");
  const mode = document.getElementById("compare-mode");
  const scrub = document.getElementById("compare-scrub");
  const setPlaying = (on) => { inStep.playing = on; play.textContent = on ? "Pause" : "Play"; };
  if (inStep.count === 0) mode.querySelector("option[value=repetition]").remove();
  mode.value = inStep.mode;
  play.disabled = false;
  play.addEventListener("click", () => setPlaying(!inStep.playing));
  scrub.max = STEPS;
  scrub.addEventListener("input", () => { setPlaying(false); inStep.seek((Number(scrub.value) / STEPS) * inStep.span()); });
  mode.addEventListener("change", () => {
    // Keep the first recording where it is: the same frame, read in the other mode's position.
    const frame = inStep.playbacks[0].frame;
    const first = inStep.metas[0];
    inStep.mode = mode.value;
    if (inStep.mode === "time") inStep.seek(frame / Math.max(1, first.frames - 1));
    else inStep.seek(positionInRepetitions(first, frame, inStep.count));
  });
}

function positionInRepetitions(meta, frame, count) {
  for (let k = 0; k < count; k++) {
    const rep = meta.repetitions[k];
    if (frame <= rep.end) return k + Math.max(0, (frame - rep.start) / Math.max(1, rep.end - rep.start));
  }
  return count;
}

async function main() {
  const roots = [...document.querySelectorAll(".compare-viewer")];
  if (roots.length !== 2) return;
  const playbacks = await Promise.all(roots.map(loadViewer));
  if (playbacks.some((p) => p === null)) return; // the message is in the viewer that failed
  const inStep = new InStep(playbacks, roots);
  wireControls(inStep);
  inStep.seek(0);
  requestAnimationFrame((t) => inStep.tick(t));
  window.physioCompare = inStep; // for the browser tests
  document.getElementById("compare-playback").dataset.ready = "1";
}

main();
