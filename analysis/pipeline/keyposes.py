"""The key-pose stages of the pipeline (thesis 004, chapters 5 and 6): landmark identification,
refining, periodic landmark sequence analysis, and repetitions from the cleaned sequence.

Repetitions are the cycles of the cleaned landmark sequence: each holds the tutor's cycle of
key-pose types and ends at the next start-type (type 1) key pose. The key poses decide how many
repetitions there are and where each one's end of range is; where the rest between two
repetitions is clear on the exercise's progress axis, the start-type key pose is moved to the
middle of that rest (the progress-axis segmenter's rule), because that is where a person cutting
the recording by hand puts the cut and a classifier's start pose drifts along a flat rest. When
the key poses hold no whole cycle at all, the progress-axis segmenter alone cuts the recording
and the result says ``segmentation = "fallback"``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.landmarks.identification import LandmarkModel, LandmarkResult, periodic_landmarks
from analysis.landmarks.key_poses import KeyPoses
from analysis.landmarks.repetitions import Repetition, repetitions
from analysis.landmarks.segmentation import (
    Segments,
    fuse_peaks,
    rest_height,
    segment,
    segments_at,
)
from analysis.pipeline.results import KeyPose, PeriodicSummary

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class KeyPoseRepetitions:
    """Repetition boundaries (``segments``), the key poses shown to the therapist (``landmarks``,
    type-1 poses at each start and after the last end), and how the cut was made."""

    segments: Segments
    landmarks: tuple[KeyPose, ...]
    segmentation: str  # "landmarks" or "fallback"


def periodic_analysis(
    model: LandmarkModel, refined: LandmarkResult, seed: int = 0
) -> tuple[KeyPoses, dict[int, str], PeriodicSummary]:
    """Chapter 6 (GA^K with the tutor's periods) on the refined landmarks: the kept members,
    each kept frame's origin (`origins`), and what the stage changed: candidates counted,
    frames removed, and frames inserted by the grammar typing to complete the cycle."""
    final = refined.landmarks
    kept = periodic_landmarks(final, model.patterns_, "ga-k", seed)
    origin = origins(refined)
    removed = sorted(set(final.frames.tolist()) - set(kept.frames.tolist()))
    summary = PeriodicSummary(
        candidates=int(refined.candidates.frames.size),
        removed=tuple(int(f) for f in removed),
        inserted=tuple(f for f in kept.frames.tolist() if origin.get(f) == "inserted"),
    )
    return kept, origin, summary


def origins(result: LandmarkResult) -> dict[int, str]:
    """Per final landmark frame: "inserted" (added by grammar typing), "identified" (a refined
    landmark that was the lone candidate of its cluster: the classifier's frame as is) or
    "refined" (chosen among candidates, or moved to the end of range)."""
    regularised = result.regularised if result.regularised is not None else result.landmarks
    refined = set(result.refined.frames.tolist())
    out = {}
    for final, before in zip(
        result.landmarks.frames.tolist(), regularised.frames.tolist(), strict=True
    ):
        if before not in refined:
            out[final] = "inserted"
        elif final != before or int((np.abs(result.candidates.frames - before) <= 1).sum()) != 1:
            out[final] = "refined"
        else:
            out[final] = "identified"
    return out


def _main_peak(rep: Repetition, height: FloatArray) -> int:
    """The repetition's end of range: of its intermediate key poses, the one highest on the
    progress axis."""
    return max(rep.peaks, key=lambda f: float(height[min(f, height.size - 1)]))


def cycles_of(kept: KeyPoses, model: LandmarkModel, n_frames: int) -> list[Repetition]:
    """Whole repetitions of the cleaned sequence (the tutor's cycle, opened and closed)."""
    reps = repetitions(
        kept.frames.tolist(), kept.types.tolist(), model.cycle_, last_frame=n_frames - 1
    )
    return [r for r in reps if r.peaks]


def key_pose_repetitions(
    kept: KeyPoses,
    origin: dict[int, str],
    model: LandmarkModel,
    progress: FloatArray,
    rep_frames: float,
) -> KeyPoseRepetitions:
    """Repetitions from the cleaned landmark sequence (see the module docstring)."""
    n = progress.size
    reps = cycles_of(kept, model, n)
    if not reps:
        return _fallback(progress, rep_frames)
    height = rest_height(progress, rep_frames)
    key_peaks = np.array([_main_peak(r, height) for r in reps], dtype=np.int64)
    peaks = fuse_peaks(height, np.clip(key_peaks, 1, max(n - 2, 1)), rep_frames)
    if peaks.size == 0:  # key-pose cycles but no movement along the exercise's axis to cut
        return _fallback(progress, rep_frames)
    segments = segments_at(height, peaks, rep_frames)
    shown = _shown(kept, origin, segments, model.cycle_[0])
    return KeyPoseRepetitions(segments, shown, "landmarks")


def _shown(
    kept: KeyPoses, origin: dict[int, str], segments: Segments, start_type: int
) -> tuple[KeyPose, ...]:
    """The cleaned key poses with each repetition's start-type pose at its start (and one after
    the last end), so start-type key poses start the repetitions."""
    kept_frames = set(kept.frames.tolist())
    marks: dict[int, KeyPose] = {}
    for frame, kind in zip(kept.frames.tolist(), kept.types.tolist(), strict=True):
        if kind != start_type:
            marks[frame] = KeyPose(frame, kind, origin.get(frame, "refined"))
    for frame in [*segments.starts.tolist(), int(segments.ends[-1])]:
        where = origin.get(frame, "refined") if frame in kept_frames else "refined"
        marks[frame] = KeyPose(int(frame), start_type, where)
    return tuple(marks[f] for f in sorted(marks))


def _fallback(progress: FloatArray, rep_frames: float) -> KeyPoseRepetitions:
    """The progress-axis cut alone; the pipeline labels its key poses."""
    return KeyPoseRepetitions(segment(progress, rep_frames), (), "fallback")
