// The exercise page's reference player: the reference recording alone, in the recording page's
// 3D viewer (viewer.js), played in a loop with a play/pause button and a time read-out.
// Data from exercises:reference-data (positions per frame, the skeleton's parents).
import { Playback } from "./viewer.js";

async function referencePlayer(box) {
  const data = await (await fetch(box.dataset.url)).json();
  const meta = { frames: data.n_frames, joints: data.joints, fps: data.fps, names: data.names,
    parents: data.parents, skeletons: [{ key: "tutor" }], assessment: [] };
  const playback = new Playback(box, meta, Float32Array.from(data.positions));
  const button = box.querySelector("button"), clock = box.querySelector("[data-clock]");
  const seconds = (frame) => (frame / data.fps).toFixed(1);
  playback.onFrame((frame) => { clock.textContent = `${seconds(frame)} s of ${seconds(data.n_frames - 1)} s`; });
  button.addEventListener("click", () => {
    playback.playing = !playback.playing;
    button.textContent = playback.playing ? "Pause" : "Play";
  });
  playback.setFrame(0);
  box.dataset.ready = "1";
  window.referencePlayer = playback;
}

const box = document.getElementById("reference-player");
if (box) referencePlayer(box);
