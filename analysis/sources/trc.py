"""OpenSim ``.trc`` marker files (OpenCap, Pose2Sim, marker labs): three header lines (file
type; ``DataRate … Units …`` names and values), the marker names line, the X/Y/Z line, then one
tab-separated row per frame (``Frame#``, ``Time``, x y z per marker; empty where not seen)."""

from __future__ import annotations

import numpy as np

from analysis.sources.errors import CaptureFileError
from analysis.sources.tables import FloatArray, check_frames, number, text_of

HEADER_LINES = 5


def read_trc(content: bytes) -> tuple[dict[str, FloatArray], float, str | None]:
    """Tracks by marker name, the frame rate (DataRate) and the unit the header names."""
    lines = text_of(content).splitlines()
    if len(lines) < HEADER_LINES + 2 or not lines[0].startswith("PathFileType"):
        raise CaptureFileError("This is not a .trc file: it lacks the PathFileType header.")
    keys = lines[1].split("\t")
    values = lines[2].split("\t")
    info = {k.strip(): v.strip() for k, v in zip(keys, values, strict=False)}
    fps = number(info.get("DataRate", ""), "The header's DataRate")
    if not np.isfinite(fps) or fps <= 0:
        raise CaptureFileError("The .trc header has no usable DataRate.")
    names = [n.strip() for n in lines[3].split("\t")[2:] if n.strip()]
    if not names:
        raise CaptureFileError("The .trc file names no markers.")
    body = [line.split("\t") for line in lines[HEADER_LINES:] if line.strip()]
    check_frames(len(body))
    width = 2 + 3 * len(names)
    data = np.full((len(body), width), np.nan)
    for r, row in enumerate(body):
        if len(row) < 2 or len(row) > width + 3:
            raise CaptureFileError(f"Frame row {r + 1} has {len(row)} values, not {width}.")
        cells = [c.strip() or "nan" for c in row[:width]]
        try:  # a whole row at once (a 100 fps take has thousands); a bad cell is named below
            data[r, : len(cells)] = np.array(cells, dtype=np.float64)
        except ValueError:
            for k, cell in enumerate(row[:width]):
                data[r, k] = number(cell.strip(), f"Frame row {r + 1}")
    tracks = {n: data[:, 2 + 3 * k : 5 + 3 * k] for k, n in enumerate(names)}
    return tracks, fps, info.get("Units")
