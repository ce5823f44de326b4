// The camera page's pose engine, behind one small contract so that another engine can replace it:
//
//   const engine = await createPoseEngine({ base, onResult });
//   engine.start(video);   // finds the body in the video's frames, one after another
//   engine.stop();         // until start again (the detector is kept: re-creating one leaks)
//   engine.model;          // "full" or "lite"
//   engine.rate();         // frames a second found over the last seconds
//   engine.useLite();      // the lighter model from now on (done by itself under 15 a second)
//   onResult({ time, world, image })
//     time:  performance.now() when the frame was taken (ms)
//     world: Float32Array(33 × 4), x y z in metres about the hips (y down) and visibility,
//            MediaPipe BlazePose's 33 landmarks; null when no person is in view
//     image: 33 { x, y, visibility }, x and y 0 to 1 across the picture; null likewise
//
// This engine is npm's @mediapipe/pose, served from the site's own static files (`base`): its
// WebAssembly and models come from this site, never another. The full model runs first; below
// 15 frames a second the lite one takes over (about a third faster). Where the graphics are
// drawn by the processor (no graphics card: SwiftShader, llvmpipe), the model runs on the
// processor's own path too, several times faster there than through emulated graphics.

const MIN_RATE = 15; // frames a second under which the lite model takes over
const LANDMARKS = 33;

function loadScript(src) {
  return new Promise((resolve, reject) => {
    if (window.Pose) return resolve();
    const script = document.createElement("script");
    script.src = src;
    script.onload = resolve;
    script.onerror = () => reject(new Error(`${src} could not be loaded`));
    document.head.append(script);
  });
}

export function softwareGraphics() {
  const gl = document.createElement("canvas").getContext("webgl2");
  if (!gl) return true;
  const info = gl.getExtension("WEBGL_debug_renderer_info");
  const renderer = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : "";
  return /swiftshader|llvmpipe|software/i.test(String(renderer));
}

function worldOf(results) {
  const world = results.poseWorldLandmarks;
  if (!world || world.length !== LANDMARKS) return null;
  const out = new Float32Array(LANDMARKS * 4);
  world.forEach((p, k) => out.set([p.x, p.y, p.z, p.visibility ?? 1], k * 4));
  return out;
}

export async function createPoseEngine({ base, onResult, fallback = true }) {
  await loadScript(`${base}pose.js`);
  const pose = new window.Pose({ locateFile: (file) => `${base}${file}` });
  const options = {
    modelComplexity: 1, smoothLandmarks: true, enableSegmentation: false,
    minDetectionConfidence: 0.5, minTrackingConfidence: 0.5,
    useCpuInference: softwareGraphics(),
  };
  pose.setOptions(options);
  let taken = 0;
  const times = [];
  pose.onResults((results) => {
    const world = worldOf(results);
    const image = world ? results.poseLandmarks.map((p) => ({ x: p.x, y: p.y, visibility: p.visibility ?? 1 })) : null;
    onResult({ time: taken, world, image });
  });
  await pose.initialize();

  const engine = { model: "full", running: false, video: null, frames: 0 };
  engine.rate = () => {
    if (times.length < 2) return 0;
    return (times.length - 1) / ((times[times.length - 1] - times[0]) / 1000);
  };
  engine.useLite = () => {
    engine.model = "lite";
    times.length = 0;
    pose.setOptions({ ...options, modelComplexity: 0 }); // the same detector, another model
  };
  function fallBack() {
    // judged on a few seconds of frames (the first ones pay for warming up)
    if (!fallback || engine.model !== "full" || engine.frames < 20 || engine.rate() >= MIN_RATE) return;
    engine.useLite();
  }
  let looping = false; // one loop at a time, whatever start and stop do meanwhile
  async function step() {
    if (!engine.running) { looping = false; return; }
    const video = engine.video;
    if (video.readyState >= 2 && video.videoWidth > 0) {
      taken = performance.now();
      await pose.send({ image: video });
      engine.frames += 1;
      times.push(performance.now());
      if (times.length > 30) times.shift();
      fallBack();
    }
    setTimeout(step, 0); // let the page draw and the socket answer between frames
  }
  engine.start = (video) => {
    engine.video = video;
    engine.running = true;
    if (!looping) { looping = true; step(); }
  };
  engine.stop = () => { engine.running = false; };
  return engine;
}
