"""Affine offset adjustment of a motion toward target key poses, and the four demonstration
skeletons (paper 004, 7.3.3, Alg 13, and 7.3).

Public API:

- ``adjust(local_q (F, J, 4), landmark_frames (L,), target_q (L, J, 4), gamma, method="rotation")
  -> (F, J, 4)``. At landmark k the full offset of joint j is the rotation D_kj = target·q⁻¹ (in
  the parent's frame, applied on the left: D·q = target). Its share γ_j, as a rotation vector
  D_kj^γ = exp(γ_j·log D_kj), is interpolated by slerp (linearly in the rotation group) between
  consecutive landmarks and held constant before the first and after the last landmark; every
  frame becomes D(f)·q(f). So γ = 0 returns the input,
  γ = 1 puts every landmark pose exactly on its target, and since the rotation distance is
  invariant under a common left factor, the jump between consecutive adjusted frames is at most
  the input's jump plus the offset's change over that frame: no gimbal lock, no flips. The offset
  turns uniformly between landmarks unless that would push a jump the input kept within
  ``max_jump_deg`` (20°) over it; then its turn is re-timed, as evenly as the caps allow
  (``water_fill``), into the frames where the input moves slowly. Only landmarks a few frames
  apart with very different targets leave too little room, and γ = 1 then demands the jump.
  ``method="euler"`` is the paper's version (offsets of Euler angles in the joint's channel
  ``order``, interpolated linearly), kept for comparison; it has the gimbal-lock artefacts of
  ch. 8.2. Two fixes to Alg 13 in both methods: its left-edge offset δ₁ multiplies the already
  applied offset by γ a second time (we carry the offset applied at the left landmark), and it
  never moves the first landmark and leaves the frames after the last one untouched (a jump); we
  adjust every landmark and hold the offset outside them. Euler differences are wrapped to ±180°.
- ``gamma_vector(gamma: Mapping[str, float], names, default=0.0) -> (J,)`` — γ per joint by name.
- ``frame_jumps(local_q) -> (F − 1, J)`` degrees between consecutive frames (for checks);
  ``channel_orders(skeleton)`` the Euler order of every joint for ``method="euler"``.
- ``Performance`` (local rotations, translations, key poses of one take) and
  ``demonstration_skeletons(skeleton, patient, tutor, mean_poses, gamma) -> Demonstration``: world
  positions (F_patient, J, 3) of the patient; the patient adjusted by γ toward the tutor's mean pose
  of each landmark's type; the tutor synchronised to the patient (``analysis.adjustment.sync``);
  and that
  synchronised tutor adjusted by ``tutor_gamma`` (default γ) toward the patient's landmark poses.
  Patient skeletons use the patient's translations, tutor skeletons the tutor's (resampled), or,
  with ``tutor_root="patient"``, the patient's root translation so that all four stand together.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.adjustment.sync import (
    sample_linear,
    sample_rotations,
    synchronise_landmarks,
    tutor_frame_map,
)
from analysis.bvh import Motion, Skeleton
from analysis.kinematics import quaternions as quat
from analysis.kinematics import rotations, translations
from analysis.kinematics.forward_kinematics import forward_positions
from analysis.landmarks import KeyPoses

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
Gamma = float | npt.ArrayLike
# The frame-to-frame rotation jump an adjustment may not newly exceed, and the margin kept below
# it so that rounding never tips a step over.
MAX_JUMP_DEG = 20.0
JUMP_MARGIN_DEG = 1e-3


def gamma_vector(
    gamma: Mapping[str, float], names: Sequence[str], default: float = 0.0
) -> FloatArray:
    """γ per joint (J,) in ``names`` order; joints without a γ get ``default`` (0: unchanged)."""
    return np.array([float(gamma.get(n, default)) for n in names], dtype=np.float64)


def frame_jumps(local_q: FloatArray) -> FloatArray:
    """Rotation angle (degrees) between consecutive frames of every joint: (F − 1, J)."""
    q = np.asarray(local_q, dtype=np.float64)
    return np.asarray(quat.angle_between(q[:-1], q[1:], degrees=True), dtype=np.float64)


def _brackets(frames: IntArray, n_frames: int) -> tuple[IntArray, IntArray, FloatArray]:
    """For every frame, the landmarks before/after it (indices) and the fraction between them;
    before the first and after the last landmark both indices are that landmark (held)."""
    f = np.arange(n_frames, dtype=np.float64)
    hi = np.searchsorted(frames, f, side="right")
    lo = np.clip(hi - 1, 0, len(frames) - 1)
    hi = np.clip(hi, 0, len(frames) - 1)
    span = (frames[hi] - frames[lo]).astype(np.float64)
    w = np.where(span > 0, (f - frames[lo]) / np.where(span > 0, span, 1.0), 0.0)
    return lo, hi, np.clip(w, 0.0, 1.0)


def _interpolate(frames: IntArray, values: FloatArray, n_frames: int) -> FloatArray:
    """Values (L, ...) at sorted landmark frames → (F, ...): linear between, held outside."""
    lo, hi, w = _brackets(frames, n_frames)
    w = w.reshape(-1, *([1] * (values.ndim - 1)))
    return (1.0 - w) * values[lo] + w * values[hi]


def _checked(
    local_q: FloatArray, frames: npt.ArrayLike, target_q: FloatArray, gamma: Gamma
) -> tuple[FloatArray, IntArray, FloatArray, FloatArray]:
    """Validated inputs with landmarks sorted by frame; γ broadcast to (J,)."""
    q = np.asarray(local_q, dtype=np.float64)
    f = np.asarray(frames, dtype=np.int64).ravel()
    t = np.asarray(target_q, dtype=np.float64).reshape(len(f), *q.shape[1:])
    g = np.broadcast_to(np.asarray(gamma, dtype=np.float64), q.shape[1:2]).copy()
    if f.size and (f.min() < 0 or f.max() >= len(q)):
        raise ValueError(f"landmark frames must lie in 0..{len(q) - 1}")
    if np.unique(f).size != f.size:
        raise ValueError("landmark frames must be distinct")
    if np.any((g < 0) | (g > 1)):
        raise ValueError("gamma must lie in [0, 1]")
    order = np.argsort(f)
    return q, f[order], t[order], g


def water_fill(capacity: FloatArray, total: float) -> FloatArray:
    """Split ``total`` over steps as evenly as the per-step ``capacity`` (n,) allows.

    Every step gets min(capacity, λ) with λ chosen so the steps add up to ``total``: the most
    uniform split that respects the caps. When even the full capacity is short of ``total`` the
    shortfall is spread evenly on top (the caps cannot all hold; the excess is kept smallest).
    """
    n = capacity.shape[0]
    room = float(capacity.sum())
    if room <= total:
        return capacity + (total - room) / n
    caps = np.sort(capacity)
    # Filling the k smallest caps completely leaves (total − their sum) for the other n − k steps.
    filled = np.concatenate(([0.0], np.cumsum(caps)[:-1]))
    levels = (total - filled) / (n - np.arange(n))
    k = int(np.argmax(levels <= caps))
    return np.minimum(capacity, levels[k])


def _segment_timing(jumps: FloatArray, turn: float, limit: float) -> FloatArray:
    """Fractions (n + 1,) from 0 to 1 of an offset turning by ``turn`` degrees over the n
    transitions whose input jumps are ``jumps`` (n,): uniform when that keeps every jump within
    ``limit``, else re-timed so that input jump + offset step stays within it where the input
    was within it (transitions already over the limit take any share)."""
    n = jumps.shape[0]
    uniform = np.linspace(0.0, 1.0, n + 1)
    if turn <= 0.0 or not np.any((jumps <= limit) & (jumps + turn / n > limit)):
        return uniform
    capacity = np.where(jumps <= limit, np.maximum(limit - JUMP_MARGIN_DEG - jumps, 0.0), np.inf)
    steps = water_fill(np.minimum(capacity, turn), turn)
    fractions = np.concatenate(([0.0], np.cumsum(steps))) / steps.sum()
    fractions[-1] = 1.0
    return fractions


def _segments_to_retime(
    jumps: FloatArray, f: IntArray, turns: FloatArray, limit: float
) -> npt.NDArray[np.bool_]:
    """(L − 1, J): whether uniform timing of a segment's turn would push one of its transitions
    that the input kept within ``limit`` over it (one vectorised test for all segments)."""
    lengths = np.diff(f)
    segment = np.repeat(np.arange(len(lengths)), lengths)  # segment of each inner transition
    inner = jumps[f[0] : f[-1]]
    over = (inner <= limit) & (inner + turns[segment] / lengths[segment, None] > limit)
    return np.logical_or.reduceat(over, f[:-1] - f[0], axis=0)


def _timing(q: FloatArray, f: IntArray, scaled: FloatArray, limit: float | None) -> FloatArray:
    """Slerp fraction (F, J) of every frame between its bracketing landmarks' offsets."""
    _, _, w = _brackets(f, len(q))
    timing = np.repeat(w[:, None], q.shape[1], axis=1)
    if limit is None or len(f) < 2:
        return timing
    jumps = frame_jumps(q)  # (F − 1, J)
    turns = quat.angle_between(scaled[:-1], scaled[1:], degrees=True)  # (L − 1, J)
    for k, j in np.argwhere(_segments_to_retime(jumps, f, turns, limit)):
        start, stop = int(f[k]), int(f[k + 1])
        fractions = _segment_timing(jumps[start:stop, j], float(turns[k, j]), limit)
        # The landmark frame `stop` starts the next bracket (fraction 0 there): leave it.
        timing[start:stop, j] = fractions[:-1]
    return timing


def _adjust_rotation(
    q: FloatArray, f: IntArray, t: FloatArray, g: FloatArray, limit: float | None
) -> FloatArray:
    offsets = quat.to_rotvec(quat.multiply(t, quat.conjugate(q[f])))  # (L, J, 3) radians
    scaled = quat.from_rotvec(offsets * g[None, :, None])  # D^γ = exp(γ·log D)
    lo, hi, _ = _brackets(f, len(q))
    # Slerp is linear in the rotation group: the offset turns along the shortest arc, by the
    # share of the turn the timing gives each frame (uniform unless a jump limit needs otherwise).
    field = quat.slerp_indexed(scaled, lo, hi, _timing(q, f, scaled, limit))
    return quat.multiply(field, q)


def channel_orders(skeleton: Skeleton) -> list[str]:
    """Each joint's Euler order from its BVH rotation channels, e.g. 'ZXY' (completed)."""
    return [
        quat.complete_order("".join(c[0] for c in channels if c.endswith("rotation")))
        for channels in skeleton.channels
    ]


def _orders(order: str | Sequence[str], n_joints: int) -> list[str]:
    return [order] * n_joints if isinstance(order, str) else [str(o) for o in order]


def _adjust_euler(
    q: FloatArray, f: IntArray, t: FloatArray, g: FloatArray, order: str | Sequence[str]
) -> FloatArray:
    out = q.copy()
    for j, joint_order in enumerate(_orders(order, q.shape[1])):
        angles = np.unwrap(quat.to_euler(q[:, j], joint_order), period=360.0, axis=0)
        delta = quat.to_euler(t[:, j], joint_order) - angles[f]
        delta = (delta + 180.0) % 360.0 - 180.0  # the short way round
        field = _interpolate(f, delta * g[j], len(q))
        out[:, j] = quat.from_euler(angles + field, joint_order)
    return quat.make_continuous(out, axis=0)


def adjust(
    local_q: FloatArray,
    landmark_frames: npt.ArrayLike,
    target_q: FloatArray,
    gamma: Gamma,
    method: str = "rotation",
    *,
    order: str | Sequence[str] = "ZXY",
    max_jump_deg: float | None = MAX_JUMP_DEG,
) -> FloatArray:
    """Alg 13 on rotations (see the module docstring): (F, J, 4) → (F, J, 4).

    ``landmark_frames`` (L,) frames, ``target_q`` (L, J, 4) the pose each should move toward,
    ``gamma`` scalar or (J,) in [0, 1]; ``order`` (Euler method only) per joint or for all;
    ``max_jump_deg`` (rotation method): re-time the offsets so that no frame-to-frame jump the
    input kept within it goes over it (None: uniform timing).
    """
    q, f, t, g = _checked(local_q, landmark_frames, target_q, gamma)
    if f.size == 0 or not np.any(g > 0):
        return q.copy()
    if method == "rotation":
        # every joint's offset and timing are its own: the joints left as they are (γ = 0,
        # most of a rig in most exercises) need no slerp at all, and stay bit-for-bit unchanged
        out = q.copy()
        moving = np.flatnonzero(g > 0)
        t_moving = np.take(t, moving, axis=1)
        adjusted = _adjust_rotation(
            np.take(q, moving, axis=1), f, t_moving, g[moving], max_jump_deg
        )
        out[:, moving] = adjusted
        return out
    if method != "euler":
        raise ValueError(f"unknown adjustment method {method!r}: use 'rotation' or 'euler'")
    out = _adjust_euler(q, f, t, g, order)
    out[:, g == 0] = q[:, g == 0]  # bit-for-bit unchanged where nothing is asked
    return out


@dataclass(frozen=True, eq=False)
class Performance:
    """One take: local rotations (F, J, 4), translations (F, J, 3) and its key poses."""

    local_q: FloatArray
    local_t: FloatArray
    key_poses: KeyPoses

    @classmethod
    def from_motion(cls, motion: Motion, key_poses: KeyPoses) -> Performance:
        return cls(rotations(motion), translations(motion), key_poses)


@dataclass(frozen=True, eq=False)
class Demonstration:
    """The four skeletons of 7.3 as world positions (F_patient, J, 3), file units, plus the
    tutor frame shown at each patient frame (F_patient,) and the landmark pairs (patient, tutor)."""

    patient: FloatArray
    patient_adjusted: FloatArray
    tutor: FloatArray
    tutor_adjusted: FloatArray
    tutor_frame_map: FloatArray
    pairs: tuple[tuple[int, int], ...]


def _toward_mean_poses(
    p: Performance, mean_poses: Mapping[int, FloatArray]
) -> tuple[IntArray, FloatArray]:
    """The patient's landmarks whose type has a tutor mean pose, and those poses (L, J, 4)."""
    types = p.key_poses.types
    keep = np.array([int(t) in mean_poses for t in types], dtype=bool)
    frames = p.key_poses.frames[keep]
    if not frames.size:
        return frames, np.zeros((0, *p.local_q.shape[1:]))
    return frames, np.stack([mean_poses[int(t)] for t in types[keep]])


def _synchronised_tutor(
    skeleton: Skeleton, patient: Performance, tutor: Performance, tutor_root: str
) -> tuple[FloatArray, FloatArray, FloatArray, list[tuple[int, int]]]:
    """The tutor on the patient's timeline: rotations, translations, frame map and pairs."""
    if tutor_root not in ("own", "patient"):
        raise ValueError(f"tutor_root must be 'own' or 'patient', got {tutor_root!r}")
    ours, theirs = patient.key_poses, tutor.key_poses
    pairs = synchronise_landmarks(ours.types, theirs.types)
    if pairs:
        fmap = tutor_frame_map(
            pairs, ours.frames, theirs.frames, len(patient.local_q), tutor_types=theirs.types
        )
    else:  # no key pose to pair (none found, or none of the tutor's types): the tutor's own pace
        fmap = np.arange(len(patient.local_q), dtype=np.float64) % len(tutor.local_q)
    tutor_t = sample_linear(tutor.local_t, fmap)
    if tutor_root == "patient":
        roots = skeleton.parents < 0
        tutor_t[:, roots] = patient.local_t[:, roots]
    return sample_rotations(tutor.local_q, fmap), tutor_t, fmap, pairs


def demonstration_skeletons(
    skeleton: Skeleton,
    patient: Performance,
    tutor: Performance,
    mean_poses: Mapping[int, FloatArray],
    gamma: Gamma,
    *,
    tutor_gamma: Gamma | None = None,
    tutor_root: str = "own",
    method: str = "rotation",
    patient_world: FloatArray | None = None,
) -> Demonstration:
    """Patient, patient adjusted toward the tutor, tutor synchronised, and that tutor adjusted
    toward the patient (see the module docstring). Both takes must use ``skeleton``'s joints.
    ``patient_world``: the patient's world positions (F, J, 3) when already computed (the
    pipeline's one forward-kinematics pass of the recording)."""
    if patient.local_q.shape[1] != tutor.local_q.shape[1]:
        raise ValueError("the patient and the tutor must have the same joints")
    orders = channel_orders(skeleton)
    frames, targets = _toward_mean_poses(patient, mean_poses)
    patient_adj = adjust(patient.local_q, frames, targets, gamma, method, order=orders)
    tutor_q, tutor_t, fmap, pairs = _synchronised_tutor(skeleton, patient, tutor, tutor_root)
    lm = patient.key_poses.frames
    tutor_g = gamma if tutor_gamma is None else tutor_gamma
    tutor_adj = adjust(tutor_q, lm, patient.local_q[lm], tutor_g, method, order=orders)
    if patient_world is None:
        patient_world = forward_positions(skeleton, patient.local_q, patient.local_t)
    return Demonstration(
        patient=patient_world,
        patient_adjusted=forward_positions(skeleton, patient_adj, patient.local_t),
        tutor=forward_positions(skeleton, tutor_q, tutor_t),
        tutor_adjusted=forward_positions(skeleton, tutor_adj, tutor_t),
        tutor_frame_map=fmap,
        pairs=tuple(pairs),
    )
