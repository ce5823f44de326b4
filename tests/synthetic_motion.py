"""Seeded synthetic performances with ground truth, for tests and documentation.

A small 15-joint skeleton (y up, centimetres, channels Zrotation Xrotation Yrotation) performs N
repetitions of a simple exercise. Each repetition goes rest → end of range → rest with a smooth
(raised-cosine) profile; the truth records every repetition's first and last frame and its key-pose
frames. Options vary what real patients vary: tempo and non-linear time warps, a reduced range of
motion, measurement noise, pauses, and which side moves first in exercises done on both sides.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, Skeleton

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

# name, parent, offset (cm)
_JOINTS: tuple[tuple[str, int, tuple[float, float, float]], ...] = (
    ("Hips", -1, (0.0, 95.0, 0.0)),
    ("Spine", 0, (0.0, 12.0, 0.0)),
    ("Chest", 1, (0.0, 20.0, 0.0)),
    ("Neck", 2, (0.0, 22.0, 0.0)),
    ("Head", 3, (0.0, 10.0, 0.0)),
    ("LeftUpperArm", 2, (18.0, 18.0, 0.0)),
    ("LeftForearm", 5, (28.0, 0.0, 0.0)),
    ("LeftHand", 6, (25.0, 0.0, 0.0)),
    ("RightUpperArm", 2, (-18.0, 18.0, 0.0)),
    ("RightForearm", 8, (-28.0, 0.0, 0.0)),
    ("RightHand", 9, (-25.0, 0.0, 0.0)),
    ("LeftUpperLeg", 0, (9.0, -5.0, 0.0)),
    ("LeftLowerLeg", 11, (0.0, -43.0, 0.0)),
    ("RightUpperLeg", 0, (-9.0, -5.0, 0.0)),
    ("RightLowerLeg", 13, (0.0, -43.0, 0.0)),
)
ROTATION = ("Zrotation", "Xrotation", "Yrotation")
ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", *ROTATION)
# Per exercise and side: (joint, Euler column 0=Z 1=X 2=Y, peak angle in degrees).
_MOVES: dict[str, dict[str, tuple[tuple[str, int, float], ...]]] = {
    "abduction": {
        "left": (("LeftUpperArm", 0, 80.0), ("LeftForearm", 0, 10.0)),
        "right": (("RightUpperArm", 0, -80.0), ("RightForearm", 0, -10.0)),
    },
    "squat": {
        "both": (
            ("LeftUpperLeg", 1, -80.0), ("RightUpperLeg", 1, -80.0),
            ("LeftLowerLeg", 1, 100.0), ("RightLowerLeg", 1, 100.0), ("Spine", 1, 25.0),
        ),
    },
}  # fmt: skip


def skeleton() -> Skeleton:
    """The synthetic skeleton (15 joints, End Sites on the head, hands and shins)."""
    names = tuple(n for n, _, _ in _JOINTS)
    ends = [4, 7, 10, 12, 14]
    return Skeleton(
        names=names,
        parents=np.array([p for _, p, _ in _JOINTS], dtype=np.int64),
        offsets=np.array([o for _, _, o in _JOINTS], dtype=np.float64),
        channels=tuple(ROOT_CHANNELS if p < 0 else ROTATION for _, p, _ in _JOINTS),
        end_site_parents=np.array(ends, dtype=np.int64),
        end_site_offsets=np.tile([0.0, -8.0, 0.0], (len(ends), 1)),
    )


@dataclass(frozen=True)
class SyntheticConfig:
    """What the generated performance looks like (defaults: a clean tutor-like take)."""

    exercise: str = "abduction"
    n_repetitions: int = 5
    fps: float = 30.0
    rep_seconds: float = 2.0
    tempo_jitter: float = 0.0  # each repetition's duration × U(1 − j, 1 + j)
    warp: float = 0.0  # non-linear time warp inside a repetition, 0 = none, < 1
    range_of_motion: float = 1.0  # fraction of the tutor's peak angles reached
    noise_deg: float = 0.0  # Gaussian noise on every rotation channel
    pause_seconds: float = 0.5  # rest between repetitions (and before the first)
    sides: tuple[str, ...] = ("left",)  # for one-sided exercises: the order of sides per cycle
    heading_deg: float = 0.0  # the subject's facing direction about the vertical axis


@dataclass(frozen=True, eq=False)
class SyntheticTruth:
    """Ground truth: repetition frames, key poses (type 1 = start, 2.. = end of range by side)."""

    rep_starts: IntArray
    rep_ends: IntArray
    rep_sides: tuple[str, ...]
    landmark_frames: IntArray
    landmark_types: IntArray
    peak_angles: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class SyntheticPerformance:
    motion: Motion
    truth: SyntheticTruth


def _profile(n: int, warp: float, rng: np.random.Generator) -> tuple[FloatArray, int]:
    """A rest→peak→rest curve in [0, 1] over n frames, time-warped, and its peak index."""
    t = np.linspace(0.0, 1.0, n)
    if warp > 0:
        # A monotone warp t → t + a·sin(πt)·(1 − t)… keeps the ends fixed and moves the peak.
        a = warp * rng.uniform(-1.0, 1.0)
        t = np.clip(t + a * np.sin(np.pi * t) / np.pi, 0.0, 1.0)
    curve = 0.5 - 0.5 * np.cos(2.0 * np.pi * t)
    return curve, int(np.argmax(curve))


def _side_types(config: SyntheticConfig) -> dict[str, int]:
    sides = config.sides if config.exercise != "squat" else ("both",)
    return {side: 2 + k for k, side in enumerate(dict.fromkeys(sides))}


def _repetition_plan(config: SyntheticConfig, rng: np.random.Generator) -> list[tuple[str, int]]:
    sides = config.sides if config.exercise != "squat" else ("both",)
    lengths = (
        config.rep_seconds
        * config.fps
        * rng.uniform(1 - config.tempo_jitter, 1 + config.tempo_jitter, config.n_repetitions)
    )
    return [(sides[k % len(sides)], max(round(n), 6)) for k, n in enumerate(lengths)]


def generate(config: SyntheticConfig = SyntheticConfig(), seed: int = 0) -> SyntheticPerformance:
    """A synthetic performance and its truth; the same seed gives the same result."""
    rng = np.random.default_rng(seed)
    sk = skeleton()
    pause = round(config.pause_seconds * config.fps)
    plan = _repetition_plan(config, rng)
    total = pause * (len(plan) + 1) + sum(n for _, n in plan)
    frames = np.zeros((total, sk.n_channels))
    frames[:, 1] = _JOINTS[0][2][1]
    frames[:, 5] = config.heading_deg  # root Yrotation (columns: X Y Z pos, Z X Y rot)
    starts, ends, marks, types = [], [], [], []
    side_type = _side_types(config)
    cursor = pause
    for side, length in plan:
        curve, peak = _profile(length, config.warp, rng)
        for joint, column, angle in _MOVES[config.exercise][side]:
            col = int(sk.channel_starts[sk.index(joint)]) + column
            frames[cursor : cursor + length, col] += config.range_of_motion * angle * curve
        starts.append(cursor)
        ends.append(cursor + length - 1)
        marks += [cursor, cursor + peak]
        types += [1, side_type[side]]
        cursor += length + pause
    marks.append(ends[-1])
    types.append(1)
    frames[:, 3:] += (
        rng.normal(0.0, config.noise_deg, frames[:, 3:].shape) if config.noise_deg else 0
    )
    truth = SyntheticTruth(
        rep_starts=np.array(starts, dtype=np.int64),
        rep_ends=np.array(ends, dtype=np.int64),
        rep_sides=tuple(side for side, _ in plan),
        landmark_frames=np.array(marks, dtype=np.int64),
        landmark_types=np.array(types, dtype=np.int64),
        peak_angles={j: a * config.range_of_motion for s in _MOVES[config.exercise].values()
                     for j, _, a in s},
    )  # fmt: skip
    return SyntheticPerformance(Motion(sk, frames, 1.0 / config.fps), truth)
