"""Warm the BVH reader while the upload page is on screen, so the first upload answers as fast
as the next ones.

A fresh server process loads the reader's compiled (numba) code on the first file it reads:
about 1.5-3 s on a loaded 2-core machine (docs/sections/bench_upload.md). Showing the upload page
starts one background read of a tiny file, once per process; by the time a person has chosen
a file, the real upload finds the code loaded.
"""

from __future__ import annotations

import logging
import threading

log = logging.getLogger(__name__)
_started = threading.Event()
FRAMES = 12
TINY_BVH = (
    "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n"
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  JOINT LeftUpLeg\n  {\n    OFFSET 10 0 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
    "    End Site\n    {\n      OFFSET 0 -40 0\n    }\n  }\n}\n"
    f"MOTION\nFrames: {FRAMES}\nFrame Time: 0.0333333\n" + "0 90 0 0 0 0 0 0 0\n" * FRAMES
).encode()


def _read_tiny_file() -> None:
    from analysis.bvh import read
    from analysis.kinematics import positions

    try:
        positions(read(TINY_BVH))
    except Exception:  # a warm-up must never disturb the page; the real upload reports errors
        log.warning("could not warm the BVH reader", exc_info=True)


def start() -> None:
    """Warm the reader in a background thread, the first time only."""
    if _started.is_set():
        return
    _started.set()
    threading.Thread(target=_read_tiny_file, name="bvh-warm-up", daemon=True).start()
