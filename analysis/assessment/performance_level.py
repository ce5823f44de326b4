"""Performance level γ per joint (paper 004, 7.2.3, eq 7.14): γⁿ = Γ(γⁿ⁻¹, levels of session n).

The paper leaves Γ open. We use exponential smoothing of the session's normalised levels:

    v = mean over the session's assessed landmarks of 1 − (level − 1)/(N_A − 1)   ∈ [0, 1]
    γⁿ = (1 − α)·γⁿ⁻¹ + α·v          (γ¹ = v for a joint's first session)

so γ = 1 means "performs like the tutor" (every landmark at level 1) and γ = 0 "every landmark at
the worst level". Why this Γ: it is bounded (a convex combination of values in [0, 1]), monotone
(better levels never lower γ), needs no state but γ itself (what the database stores per patient,
exercise and joint), forgets old sessions geometrically (a session k sessions ago weighs α(1−α)ᵏ),
and one bad session (a bad day, a mis-detected landmark) moves γ by at most α. α = 0.3 gives a
half-life of about two sessions: a real change shows within 3–4 sessions. It converges to v when
the sessions stay at v, with |γⁿ − v| = (1 − α)ⁿ⁻¹·|γ¹ − v|.

Public API: ``session_value(levels, n_levels) -> float | None`` and
``update_levels(previous, levels, n_levels=4, smoothing=0.3) -> dict[str, float]``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np


def session_value(levels: Sequence[int], n_levels: int = 4) -> float | None:
    """Mean normalised level of one joint in one session, in [0, 1] (1 = as the tutor).

    Levels ≤ 0 (not assessed) are ignored; None when nothing was assessed. Raises ValueError for
    a level above ``n_levels``.
    """
    if n_levels < 2:
        raise ValueError("n_levels must be at least 2")
    arr = np.asarray(levels, dtype=np.int64).ravel()
    arr = arr[arr > 0]
    if arr.size == 0:
        return None
    if arr.max() > n_levels:
        raise ValueError(f"assessment levels must lie in 1..{n_levels}, got {int(arr.max())}")
    return float(np.mean(1.0 - (arr - 1) / (n_levels - 1)))


def update_levels(
    previous: Mapping[str, float] | None,
    levels: Mapping[str, Sequence[int]],
    n_levels: int = 4,
    smoothing: float = 0.3,
) -> dict[str, float]:
    """Γ: the new γ per joint from the previous γ (None for a first session) and this session's
    levels per joint. Joints not assessed this session keep their previous γ."""
    if not 0.0 < smoothing <= 1.0:
        raise ValueError("smoothing must lie in (0, 1]")
    out = {name: float(np.clip(g, 0.0, 1.0)) for name, g in (previous or {}).items()}
    for joint, joint_levels in levels.items():
        value = session_value(joint_levels, n_levels)
        if value is None:
            continue
        old = out.get(joint)
        out[joint] = value if old is None else (1.0 - smoothing) * old + smoothing * value
    return out
