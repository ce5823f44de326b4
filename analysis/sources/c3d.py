"""C3D marker files (marker labs: Vicon, Qualisys, Motion Analysis) through ``ezc3d``.

Plug-in Gait labels (LASI, RASI, …) are turned into joint centres by `analysis.sources.markers`;
other labels are looked up as keypoint names (a C3D written by a markerless system).

``ezc3d`` is compiled code that can crash the whole process on a damaged file (a fuzzed C3D
ends it with a segmentation fault), so it runs in a short-lived child interpreter that only
imports numpy and ezc3d: a crash there is an unreadable file here, never a dead web worker.
"""

from __future__ import annotations

import io
import subprocess
import sys

import numpy as np

from analysis.sources.errors import CaptureFileError
from analysis.sources.tables import FloatArray, check_frames

MAGIC_BYTE = 0x50  # the second byte of every C3D file
CHILD_SECONDS = 60
# The child: C3D bytes on stdin, an .npz of labels, rate, units and points on stdout.
CHILD = """
import io, os, sys, tempfile
import ezc3d, numpy as np
content = sys.stdin.buffer.read()
with tempfile.NamedTemporaryFile(suffix=".c3d", delete=False) as handle:
    handle.write(content)
try:
    data = ezc3d.c3d(handle.name)
finally:
    os.unlink(handle.name)
point = data["parameters"]["POINT"]
units = point["UNITS"]["value"][0] if "UNITS" in point else ""
out = io.BytesIO()
np.savez(out, labels=np.array([str(x).strip() for x in point["LABELS"]["value"]]),
         rate=np.asarray(point["RATE"]["value"], dtype=float).ravel()[:1],
         units=np.array(str(units).strip()), points=np.asarray(data["data"]["points"], float))
sys.stdout.buffer.write(out.getvalue())
"""


def read_c3d(content: bytes) -> tuple[dict[str, FloatArray], float, str | None]:
    """Tracks by marker label (file units; NaN where not seen), the frame rate and the unit."""
    if len(content) < 512 or content[1] != MAGIC_BYTE:
        raise CaptureFileError("This is not a C3D file (its header is missing).")
    try:
        done = subprocess.run(
            [sys.executable, "-c", CHILD], input=content, capture_output=True,
            timeout=CHILD_SECONDS, check=False,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        raise CaptureFileError("The C3D file could not be read in time.") from None
    if done.returncode != 0:
        raise CaptureFileError("The C3D file is damaged: its markers cannot be read.")
    return _tracks(done.stdout)


def _tracks(npz: bytes) -> tuple[dict[str, FloatArray], float, str | None]:
    try:
        with np.load(io.BytesIO(npz), allow_pickle=False) as data:
            labels = [str(x) for x in data["labels"]]
            rate = float(data["rate"][0]) if data["rate"].size else float("nan")
            units = str(data["units"]) or None
            values = np.asarray(data["points"], dtype=np.float64)
    except (OSError, KeyError, ValueError, IndexError):
        raise CaptureFileError("The C3D file has no marker positions.") from None
    if values.ndim != 3 or values.shape[1] != len(labels) or not labels:
        raise CaptureFileError("The C3D file's marker labels and positions do not agree.")
    check_frames(values.shape[2])
    if not np.isfinite(rate) or rate <= 0:
        raise CaptureFileError("The C3D file has no usable frame rate.")
    tracks = {name: values[:3, k, :].T.copy() for k, name in enumerate(labels)}
    return tracks, rate, units
