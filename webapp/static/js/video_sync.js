// The recording's phone video beside the 3D skeletons, in step with them.
//
// Skeleton frame f is the video at f / fps seconds: the motion made from a video keeps the video's
// duration and first frame (the analysis resamples it to the reference's rate, which `fps`, the
// playback's rate, already is). While playing, the video is the clock the skeletons follow
// (viewer.js `Playback.clock`), so they never drift apart; playing, pausing and seeking either
// one moves the other. A video this browser cannot play is let go: the skeletons play alone.

// Half a frame: closer than this, the video already shows the skeletons' frame.
const HALF_FRAME = 0.5;
const CANNOT_PLAY = "This browser cannot play this video; the skeletons play on their own.";

export function linkVideo(playback, video) {
  const fps = playback.meta.fps;
  let linked = true;
  const frameOfVideo = () => video.currentTime * fps;
  const seekVideo = (frame) => {
    if (!linked) return;
    const end = Number.isFinite(video.duration) ? video.duration : Infinity;
    const seconds = Math.min(frame / fps, end);
    if (Math.abs(video.currentTime - seconds) * fps > HALF_FRAME) video.currentTime = seconds;
  };
  const unlink = () => {
    if (!linked) return;
    linked = false;
    playback.clock = null; // the skeletons count their own frames again
    const label = document.getElementById("video-label");
    if (label) label.textContent = CANNOT_PLAY;
  };
  video.muted = true; // never sound on its own; the viewer may turn it on with the controls
  playback.clock = { frame: frameOfVideo, seek: seekVideo };
  video.addEventListener("error", unlink);
  if (video.error) unlink();

  // The skeletons' side: buttons, the timeline, the charts and the loop start, stop and seek.
  playback.onPlaying((on) => {
    if (!linked) return;
    if (on && video.paused) {
      seekVideo(playback.frame);
      // AbortError: a pause came first, nothing to undo; anything else: the video cannot play.
      video.play().catch((error) => { if (error.name !== "AbortError") unlink(); });
    } else if (!on && !video.paused) {
      video.pause();
    }
  });
  playback.onFrame((frame) => { if (!playback.playing) seekVideo(frame); });
  const speed = document.getElementById("speed");
  if (speed) speed.addEventListener("change", () => { video.playbackRate = Number(speed.value); });

  // The video's side: its own controls play, pause and seek the skeletons.
  video.addEventListener("play", () => { if (linked) playback.playing = true; });
  video.addEventListener("pause", () => { if (linked) playback.playing = false; });
  const follow = () => {
    const frame = Math.round(frameOfVideo());
    if (linked && !playback.playing && frame !== playback.frame) playback.setFrame(frame);
  };
  video.addEventListener("seeked", follow);
  video.addEventListener("timeupdate", follow);
  return video;
}
