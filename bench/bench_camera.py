"""The camera page's two costs, in one run on this machine:

1. Landmarks to words through the server: the MediaPipe world landmarks of the phone video of two
   squats (tests/live/fixtures, what the browser's pose engine sends), at 15 frames a second in
   binary messages of one frame, through `manage.py runserver` (what `make run` serves) into a
   camera session of a squat exercise: per message, sent → its answer received (p50, p95), and
   the same for the messages whose answer carries a repetition's words.
2. The browser's pose frames per second: Debian's Chromium (headless, software graphics), the fake
   camera playing the same video, the site's own pose module (`webapp/static/js/camera_pose.js`)
   with the full and then the lite model, each for ``--seconds``.

    .venv/bin/python -m bench.bench_camera [--seconds 20]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from analysis.live.frames import encode_frames
from bench.bench_live import create_session, free_port, machine, start_server, stop_server

ROOT = Path(__file__).resolve().parents[1]
LANDMARKS = ROOT / "tests/live/fixtures/side_squat_world_landmarks.npz"
CHROMIUM = Path(os.environ.get("CHROMIUM", "/usr/bin/chromium"))
SETUP = """
import json, django
django.setup()
from django.core.management import call_command
call_command("migrate", verbosity=0, interactive=False)
from django.core.files.base import ContentFile
from tests.analysis.fixtures.capture import make_squat_reference as squat
from tests.personas import make_world
from webapp.accounts.tokens import issue_token
from webapp.exercises.models import Exercise
from workers.exercise_models import load_or_build
w = make_world()
exercise = Exercise(clinic=w.clinic, name="Back squat",
                    tutor_landmark_frames=list(squat.KEY_POSE_FRAMES),
                    tutor_landmark_types=list(squat.KEY_POSE_TYPES),
                    landmark_type_names={"1": "start", "2": "end of range"})
exercise.tutor_file.save("tutor.bvh.gz", ContentFile(squat.REFERENCE.read_bytes()), save=False)
exercise.save()
load_or_build(exercise)  # fitted and stored now, so the server only loads it
_, key = issue_token(w.therapist, "bench")
print(json.dumps({"token": key, "patient": str(w.patient.pk), "exercise": str(exercise.pk)}))
"""
STATIC = {"/static/js/": ROOT / "webapp/static/js",
          "/static/vendor/mediapipe/pose/": ROOT / "node_modules/@mediapipe/pose"}  # fmt: skip
TYPES = {".js": "text/javascript", ".wasm": "application/wasm", ".html": "text/html"}


def percentile(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) if values else float("nan")


async def stream_landmarks(url: str, token: str, fps: float) -> tuple[list[float], list[float]]:
    """Round trips (ms) of every message and of those answered with a repetition."""
    from websockets.asyncio.client import connect

    data = np.load(LANDMARKS)
    world = data["world"].astype(np.float64)
    values = np.concatenate([world, np.ones((*world.shape[:2], 1))], axis=2).reshape(len(world), -1)
    every, words = [], []
    headers = {"Authorization": f"Token {token}"}
    async with connect(url, additional_headers=headers, max_size=None) as ws:
        await ws.send(json.dumps({"type": "start", "source": "camera", "fps": fps}))
        json.loads(await ws.recv())
        begin = time.perf_counter()
        for seq, frame in enumerate(values):
            await asyncio.sleep(max(0.0, begin + seq / fps - time.perf_counter()))
            sent = time.perf_counter()
            await ws.send(encode_frames(seq, frame[None]))
            answer = json.loads(await ws.recv())
            ms = (time.perf_counter() - sent) * 1000.0
            every.append(ms)
            if any(e.get("event") == "repetition" for e in answer):
                words.append(ms)
        await ws.send(json.dumps({"type": "end"}))
        while True:  # the repetitions the look-ahead held, then the summary
            last = json.loads(await ws.recv())
            if isinstance(last, dict) and last.get("event") == "summary":
                break
    return every, words


def server_latency(fps: float) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as folder:
        env = {k: v for k, v in os.environ.items() if k not in ("REDIS_URL", "DATABASE_URL")}
        env.update(DATA_DIR=folder, DJANGO_SETTINGS_MODULE="webapp.settings", PYTHONPATH=str(ROOT))
        out = subprocess.run(
            [sys.executable, "-c", SETUP], env=env, cwd=ROOT, check=True, capture_output=True,
            text=True,
        )  # fmt: skip
        world = json.loads(out.stdout.strip().splitlines()[-1])
        port = free_port()
        proc = start_server("runserver", env, port, Path(folder) / "server.log")
        try:
            base = f"http://127.0.0.1:{port}"
            path = create_session(base, world)
            every, words = asyncio.run(
                stream_landmarks(f"ws://127.0.0.1:{port}{path}", world["token"], fps)
            )
        finally:
            stop_server(proc)
    return {
        "messages": len(every), "p50": percentile(every, 50), "p95": percentile(every, 95),
        "repetitions": len(words), "words_p50": percentile(words, 50),
        "words_p95": percentile(words, 95),
    }  # fmt: skip


PAGE = """
<!doctype html><html><body><video id="v" muted playsinline></video>
<script type="module">
import { createPoseEngine } from "/static/js/camera_pose.js";
const video = document.getElementById("v");
video.srcObject = await navigator.mediaDevices.getUserMedia({ video: true });
await video.play();
window.engine = await createPoseEngine({ base: "/static/vendor/mediapipe/pose/",
  onResult: () => {}, fallback: false });
window.engine.start(video);
</script></body></html>
"""


def serve(route) -> None:
    """The page and the site's static files, from the repository (no server, no other host)."""
    path = route.request.url.split("localhost", 1)[1].split("/", 1)[1]
    path = "/" + path
    if path == "/bench":
        route.fulfill(body=PAGE, content_type="text/html")
        return
    for prefix, folder in STATIC.items():
        if path.startswith(prefix):
            file = folder / path[len(prefix) :]
            kind = TYPES.get(file.suffix, "application/octet-stream")
            route.fulfill(body=file.read_bytes(), content_type=kind)
            return
    route.fulfill(status=404, body="")


def browser_fps(seconds: float) -> dict[str, float]:
    """Frames a second the pose module finds with each model, on the fake camera's clip."""
    from playwright.sync_api import sync_playwright

    from tests.live.camera_clips import squat_clip

    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as folder, sync_playwright() as playwright:
        clip, _ = squat_clip(Path(folder) / "clip.y4m", slower=1.0, step=1)
        browser = playwright.chromium.launch(
            executable_path=str(CHROMIUM), headless=True,
            args=["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--use-fake-ui-for-media-stream", "--use-fake-device-for-media-stream",
                  f"--use-file-for-fake-video-capture={clip}"],
        )  # fmt: skip
        try:
            page = browser.new_page()
            page.route("**/*", serve)
            page.goto("http://localhost/bench")
            page.wait_for_function("window.engine && window.engine.frames > 5", timeout=180_000)
            for model in ("full", "lite"):
                if model == "lite":
                    page.evaluate("window.engine.useLite()")
                page.wait_for_timeout(seconds * 1000)
                out[model] = page.evaluate("window.engine.rate()")
        finally:
            browser.close()
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--fps", type=float, default=15.0)
    args = parser.parse_args(argv)
    load = os.getloadavg()[0]
    latency = server_latency(args.fps)
    fps = browser_fps(args.seconds)
    print(f"{machine()}; load average at start {load:.1f}")
    print(
        f"landmarks -> answer through the server: {latency['messages']} messages, "
        f"p50 {latency['p50']:.1f} ms, p95 {latency['p95']:.1f} ms; "
        f"with a repetition's words ({latency['repetitions']}): p50 {latency['words_p50']:.1f} ms, "
        f"p95 {latency['words_p95']:.1f} ms"
    )
    print(
        f"browser pose: full model {fps['full']:.1f} frames/s, "
        f"lite model {fps['lite']:.1f} frames/s"
    )


if __name__ == "__main__":
    main()
