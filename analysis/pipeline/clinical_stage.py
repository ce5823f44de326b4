"""The clinical stage: the clinical measures in the form the pipeline stores them, small and
rounded (the measures themselves are `analysis.clinical`'s).

- `repetition_angles(series, repetitions)`: each repetition with its angle ranges (0.1°).
- `lost_at_rate(lost, frame_time, motion)`: the frames where the capture lost a joint (marked at
  import, `analysis.sources.ImportedRecording.lost_frames`) on the frames the analysis measures.
- `workspace_summaries(motion, involved_joints)`: per hand, the reachable workspace (relative
  area, total and per quadrant) and a hull decimated to at most `MAX_HULL_VERTICES` vertices,
  only when the exercise involves an arm joint; ``{}`` otherwise.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import replace

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion
from analysis.clinical.angles import angle_ranges
from analysis.clinical.body import Body, FloatArray
from analysis.clinical.labels import involves_arms
from analysis.clinical.results import AngleRange, WorkspaceSummary
from analysis.clinical.workspace import Workspace, covered_patch, reachable_workspace
from analysis.kinematics import Kinematics
from analysis.pipeline.results import RepetitionResult

BoolArray = npt.NDArray[np.bool_]
MAX_HULL_VERTICES = 32  # 96 coordinates and about 170 face indices per hand


def rounded(angles: Mapping[str, AngleRange], digits: int = 1) -> dict[str, AngleRange]:
    return {k: AngleRange(round(v.min, digits), round(v.max, digits)) for k, v in angles.items()}


def repetition_angles(
    series: Mapping[str, FloatArray], repetitions: Iterable[RepetitionResult]
) -> tuple[RepetitionResult, ...]:
    """The repetitions with ``clinical_angles``: each angle's range over the repetition's
    frames (start..end inclusive), rounded to 0.1° to keep the stored summary small."""
    return tuple(
        replace(rep, clinical_angles=rounded(angle_ranges(dict(series), rep.start, rep.end)))
        for rep in repetitions
    )


def lost_at_rate(
    lost: Mapping[str, BoolArray], frame_time: float, motion: Motion
) -> dict[str, BoolArray]:
    """Per joint, the frames of ``lost`` (the recording's own frames, ``frame_time`` s apart)
    on the frames of ``motion`` (the recording at the model's rate): a frame is lost where
    either recorded frame it lies between is (the same frames at the same rate)."""
    at_rate: dict[str, BoolArray] = {}
    for joint, frames in lost.items():
        marked = np.asarray(frames, dtype=bool)
        # rounded: at the same rate k·t/t must stay k, not a hair above it (the next frame)
        where = np.round(np.arange(motion.n_frames) * motion.frame_time / frame_time, 6)
        where = np.clip(where, 0, marked.size - 1)
        at_rate[joint] = marked[np.floor(where).astype(int)] | marked[np.ceil(where).astype(int)]
    return at_rate


def farthest_points(points: FloatArray, count: int) -> FloatArray:
    """``count`` of the points spread as far apart as possible (greedy, from the first)."""
    if len(points) <= count:
        return points
    chosen = [0]
    distance = np.linalg.norm(points - points[0], axis=1)
    while len(chosen) < count:
        chosen.append(int(np.argmax(distance)))
        distance = np.minimum(distance, np.linalg.norm(points - points[chosen[-1]], axis=1))
    return points[sorted(chosen)]


def small_hull(ws: Workspace, max_vertices: int = MAX_HULL_VERTICES) -> WorkspaceSummary:
    """The workspace with its hull decimated for display (areas are the full hull's)."""
    vertices, faces = ws.vertices, ws.faces
    if len(vertices) > max_vertices:
        vertices, faces = covered_patch(farthest_points(vertices, max_vertices))
    coords = np.round(np.asarray(vertices, dtype=np.float32).astype(np.float64), 3)
    return WorkspaceSummary(
        side=ws.side,
        relative_area=round(float(ws.relative_area), 4),
        quadrants={k: round(float(v), 4) for k, v in ws.quadrants.items()},
        vertices=tuple((float(x), float(y), float(z)) for x, y, z in coords),
        faces=tuple((int(a), int(b), int(c)) for a, b, c in faces),
    )


def workspace_summaries(
    motion: Motion,
    involved_joints: Iterable[str],
    seen: tuple[Kinematics, Body] | None = None,
) -> dict[str, WorkspaceSummary]:
    """Per hand the stored workspace, for exercises that involve an arm joint only; ``seen``:
    the motion's kinematics and body parts when already computed."""
    if not involves_arms(involved_joints):
        return {}
    kin, body = seen if seen is not None else (None, None)
    hands = reachable_workspace(motion, kin=kin, body=body)
    return {side: small_hull(ws) for side, ws in hands.items()}
