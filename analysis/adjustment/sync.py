"""Landmark and motion synchronisation of a user with a tutor (paper 004, 7.3.1–7.3.2).

Public API:

- ``synchronise_landmarks(user_types, tutor_types, repeat_tutor=True) -> list[(u, t)]`` — Alg 11:
  pairs (user landmark index, tutor landmark index) of the same type. Each user landmark, in time
  order, takes the first *unassigned* tutor landmark of its type found by scanning the tutor's
  landmarks cyclically from the one after the last assigned. A user landmark with no such tutor
  landmark stays unpaired, so missing, extra and reordered landmarks only lose pairs locally.
  ``repeat_tutor`` (our addition) makes a type's tutor landmarks available again once all of them
  are used, so a user doing more repetitions than the tutor is paired with the tutor replayed.
- ``tutor_frame_map(pairs, user_frames, tutor_frames, n_user_frames) -> (n_user_frames,) float`` —
  Alg 12 with eq 7.17: the (fractional) tutor frame to show at every user frame.
- ``sample_rotations(local_q, frame_map) -> (len(map), J, 4)`` (slerp) and
  ``sample_linear(values, frame_map)`` (translations): the tutor resampled on the user's timeline.

Eq 7.17 maps user frame ``u_a + i`` (``i = 1..|SS_P|``) to tutor frame ``t_a + i·|SS_T|/|SS_P|``,
which is the straight line through (u_a, t_a) and (u_b, t_b); we keep it fractional and
interpolate instead of truncating, so the resampled tutor moves smoothly. Frames before the first
pair hold the first pair's tutor frame, frames after the last pair hold the last one's. Alg 12
drops a segment whose tutor frames go backwards; we need a tutor frame for every user frame, so
such a segment (the tutor wrapping round, or landmarks done in another order) is first re-anchored
on a same-type tutor landmark that keeps time moving forwards (``_forward_segment``), and if there
is none the tutor holds the segment's start frame and jumps at its end.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numba as nb
import numpy as np
import numpy.typing as npt

from analysis.kinematics import quaternions as quat

FloatArray = npt.NDArray[np.float64]
Pair = tuple[int, int]


def _next_match(
    tutor_types: Sequence[int], assigned: list[bool], wanted: int, last: int
) -> int | None:
    """First unassigned tutor landmark of type ``wanted`` after ``last``, cyclically."""
    n = len(tutor_types)
    for step in range(1, n + 1):
        k = (last + step) % n
        if tutor_types[k] == wanted and not assigned[k]:
            return k
    return None


def synchronise_landmarks(
    user_types: npt.ArrayLike, tutor_types: npt.ArrayLike, *, repeat_tutor: bool = True
) -> list[Pair]:
    """Alg 11: pairs (user index, tutor index) of same-type landmarks, in user order.

    Types are (L,) ints (lists or arrays); see the module docstring for the rule."""
    tutor = [int(t) for t in np.asarray(tutor_types, dtype=np.int64).ravel()]
    assigned = [False] * len(tutor)
    last = len(tutor) - 1  # so that the scan starts at the tutor's first landmark
    pairs: list[Pair] = []
    for u, wanted in enumerate(int(t) for t in np.asarray(user_types, dtype=np.int64).ravel()):
        k = _next_match(tutor, assigned, wanted, last)
        if k is None and repeat_tutor and wanted in tutor:
            for i, t in enumerate(tutor):
                assigned[i] = assigned[i] and t != wanted
            k = _next_match(tutor, assigned, wanted, last)
        if k is None:
            continue
        assigned[k] = True
        last = k
        pairs.append((u, k))
    return pairs


def _forward_segment(
    t_a: int, t_b: int, tutor_frames: FloatArray, tutor_types: npt.ArrayLike | None
) -> tuple[float, float] | None:
    """Re-anchor a backward segment (tutor landmark t_a → t_b, frame of t_b before t_a's) so that
    the tutor goes forwards: t_a's type latest before t_b, else t_b's type first after t_a."""
    if tutor_types is None:
        return None
    fa, fb = tutor_frames[t_a], tutor_frames[t_b]
    types = np.asarray(tutor_types)
    before = np.flatnonzero((types == types[t_a]) & (tutor_frames < fb))
    if before.size:
        return float(tutor_frames[before[-1]]), float(fb)
    after = np.flatnonzero((types == types[t_b]) & (tutor_frames > fa))
    if after.size:
        return float(fa), float(tutor_frames[after[0]])
    return None


def tutor_frame_map(
    pairs: Sequence[Pair],
    user_frames: npt.ArrayLike,
    tutor_frames: npt.ArrayLike,
    n_user_frames: int,
    *,
    tutor_types: npt.ArrayLike | None = None,
) -> FloatArray:
    """Alg 12 / eq 7.17: fractional tutor frame for every user frame, (n_user_frames,).

    ``pairs`` index ``user_frames`` / ``tutor_frames`` (landmark frames, in frames). Give
    ``tutor_types`` to let backward segments be re-anchored (see the module docstring).
    """
    uf = np.asarray(user_frames, dtype=np.float64)
    tf = np.asarray(tutor_frames, dtype=np.float64)
    if not pairs:
        raise ValueError("no synchronised landmark pair: the user and the tutor share no type")
    ordered = sorted(pairs, key=lambda p: (uf[p[0]], p[0]))
    out = np.full(n_user_frames, tf[ordered[0][1]])
    frames = np.arange(n_user_frames, dtype=np.float64)
    for (ua, ta), (ub, tb) in itertools.pairwise(ordered):
        u0, u1 = uf[ua], uf[ub]
        if u1 <= u0:
            continue
        t0, t1 = float(tf[ta]), float(tf[tb])
        if t1 < t0:
            t0, t1 = _forward_segment(ta, tb, tf, tutor_types) or (t0, t0)
        span = (frames > u0) & (frames <= u1)
        out[span] = t0 + (frames[span] - u0) * (t1 - t0) / (u1 - u0)
        out[frames == u1] = tf[tb]  # the landmark itself always shows its partner
    out[frames > uf[ordered[-1][0]]] = tf[ordered[-1][1]]
    return out


def _split(frame_map: FloatArray, n_frames: int) -> tuple[npt.NDArray[np.int64], FloatArray]:
    """Lower frame index and fraction of every (clipped) fractional frame."""
    f = np.clip(np.asarray(frame_map, dtype=np.float64), 0.0, n_frames - 1.0)
    lo = np.minimum(np.floor(f).astype(np.int64), max(n_frames - 2, 0))
    return lo, f - lo


def sample_rotations(local_q: FloatArray, frame_map: FloatArray) -> FloatArray:
    """Rotations (F, J, 4) sampled at fractional frames by slerp: (len(frame_map), J, 4)."""
    q = np.asarray(local_q, dtype=np.float64)
    if q.shape[0] == 1:
        return np.repeat(q, len(frame_map), axis=0)
    lo, frac = _split(frame_map, q.shape[0])
    frac_j = np.repeat(frac[:, None], q.shape[1], axis=1)
    return quat.slerp_indexed(q, lo, lo + 1, frac_j)


def sample_linear(values: FloatArray, frame_map: FloatArray) -> FloatArray:
    """Any (F, ...) series (e.g. translations (F, J, 3)) sampled linearly: (len(frame_map), ...)."""
    v = np.asarray(values, dtype=np.float64)
    if v.shape[0] == 1:
        return np.repeat(v, len(frame_map), axis=0)
    lo, frac = _split(frame_map, v.shape[0])
    rows = np.ascontiguousarray(v.reshape(v.shape[0], -1))
    return _lerp_rows(rows, lo, frac).reshape(len(lo), *v.shape[1:])


@nb.njit(cache=True, nogil=True)
def _lerp_rows(v: FloatArray, lo: npt.NDArray[np.int64], w: FloatArray) -> FloatArray:
    """out[i] = (1 - w[i]) v[lo[i]] + w[i] v[lo[i] + 1], each product and the sum rounded as
    numpy's expression rounds them, without its four frame-sized temporaries."""
    out = np.empty((lo.size, v.shape[1]))
    for i in range(lo.size):
        a, b, wi = v[lo[i]], v[lo[i] + 1], w[i]
        keep = 1.0 - wi
        for c in range(v.shape[1]):
            out[i, c] = keep * a[c] + wi * b[c]
    return out
