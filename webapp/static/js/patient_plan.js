// Today's plan (the patient's home): each prescribed exercise's reference movement playing in 3D,
// drawn by the recording page's viewer (viewer.js) from dashboard:my-reference. A Pause button
// stops it (moving content must be stoppable); it starts paused when the person asks for less
// motion.
import { Playback } from "./viewer.js";

async function show(box) {
  const status = box.querySelector(".reference-status");
  const button = box.querySelector(".reference-play");
  try {
    const response = await fetch(box.dataset.url, { headers: { Accept: "application/json" } });
    if (!response.ok) throw new Error(`HTTP ${response.status}`);
    const data = await response.json();
    const meta = { frames: data.frames, joints: data.names.length, fps: data.fps, names: data.names,
      parents: data.parents, skeletons: [{ key: "tutor" }], assessment: [] };
    const playback = new Playback(box, meta, Float32Array.from(data.positions));
    const setPlaying = (playing) => {
      playback.playing = playing;
      button.textContent = playing ? "Pause" : "Play";
    };
    setPlaying(!window.matchMedia("(prefers-reduced-motion: reduce)").matches);
    button.addEventListener("click", () => setPlaying(!playback.playing));
    button.hidden = false;
    status.textContent = "";
    box.dataset.ready = "1";
  } catch (error) {
    status.textContent = "The movement could not be shown just now.";
    box.dataset.ready = "failed";
  }
}

document.querySelectorAll(".reference-view").forEach(show);
