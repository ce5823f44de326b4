"""Streaming aligners: Open-End DTW equals the offline open-end answer; forward plotting is
monotonic, obeys Type V and tracks a warped copy."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from analysis.dtw import DTWOptions, align, cost_matrix
from analysis.kinematics import quaternions as quat
from analysis.online.aligners import (
    ForwardPlotAligner,
    ForwardPlotOptions,
    OpenEndAligner,
    TypeV,
    forecast,
    method_b_step,
    reverse_accumulate,
)

STREAM_OPTIONS = [
    DTWOptions(),
    DTWOptions(path_length_weighting=True),
    DTWOptions(step="type-v"),
    DTWOptions(window=3),
    DTWOptions(open_begin=True, path_length_weighting=True),
    DTWOptions(cost="sqeuclidean", weights=(2.0, 0.5, 1.0), window=4, step="type-v"),
]


@pytest.mark.parametrize("opt", STREAM_OPTIONS)
def test_open_end_push_equals_offline_open_end(opt: DTWOptions) -> None:
    rng = np.random.default_rng(0)
    x, y = rng.standard_normal((18, 3)), rng.standard_normal((15, 3))
    oa = OpenEndAligner(y, opt)
    for t in range(len(x)):
        j = oa.push(x[t])
        try:
            offline = align(x[: t + 1], y, replace(opt, open_end=True))
        except ValueError:
            continue
        assert j == offline.end
        np.testing.assert_array_equal(oa.path(), offline.path)


def test_open_end_row_is_the_dtw_cost_against_each_prefix() -> None:
    rng = np.random.default_rng(1)
    x, y = rng.standard_normal((9, 2)), rng.standard_normal((7, 2))
    oa = OpenEndAligner(y)
    for f in x:
        oa.push(f)
    row = oa.row()
    for j in range(len(y)):
        assert row[j] == pytest.approx(align(x, y[: j + 1]).cost, rel=1e-12)


def test_open_end_grows_beyond_initial_capacity_and_is_fast_enough() -> None:
    rng = np.random.default_rng(2)
    y = rng.standard_normal((40, 66))
    oa = OpenEndAligner(y, DTWOptions(path_length_weighting=True))
    x = y[np.repeat(np.arange(40), 3)] + 0.01 * rng.standard_normal((120, 66))
    out = [oa.push(f) for f in x]
    assert out[-1] == 39 and oa.path().shape[1] == 2
    with pytest.raises(ValueError):
        OpenEndAligner(y, keep_path=False).path()


def warped_pair(n_ref: int = 300, n_query: int = 390) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.linspace(0, 4 * np.pi, n_ref)
    ref = np.stack([np.sin(t), np.cos(2 * t), np.sin(0.5 * t)], axis=1)
    u = np.linspace(0.0, 1.0, n_query)
    warp = (u + 0.08 * np.sin(2 * np.pi * u)) * (n_ref - 1)
    query = np.stack([np.interp(warp, np.arange(n_ref), ref[:, k]) for k in range(3)], axis=1)
    return ref, query + 0.01 * np.random.default_rng(3).standard_normal(query.shape), warp


@pytest.mark.parametrize("method", ["A", "B", "C"])
@pytest.mark.parametrize("step", ["symmetric", "type-v"])
def test_forward_plotting_is_monotonic_and_tracks_a_warp(method: str, step: str) -> None:
    ref, query, warp = warped_pair()
    fa = ForwardPlotAligner(
        ref,
        ForwardPlotOptions(method=method, window=20),
        DTWOptions(step=step),  # type: ignore[arg-type]
    )
    mapping = np.array([fa.push(f) for f in query])
    steps = np.diff(mapping)
    assert np.all(steps >= 0)
    assert np.median(np.abs(mapping - warp)) <= 3.0
    if step == "type-v":
        assert steps.max() <= 3
        zeros = "".join("0" if s == 0 else "x" for s in steps)
        assert "000" not in zeros.rstrip("0")  # the end of the reference may hold


def test_method_c_with_path_length_weighting_tracks_too() -> None:
    ref, query, warp = warped_pair()
    fa = ForwardPlotAligner(
        ref, ForwardPlotOptions(window=15), DTWOptions(step="type-v", path_length_weighting=True)
    )
    mapping = np.array([fa.push(f) for f in query])
    assert np.median(np.abs(mapping - warp)) <= 3.0


def test_type_v_state_table() -> None:
    tv = TypeV()
    assert tv.allowed() == (0, 1, 2, 3)
    tv.advance(0)
    assert tv.allowed() == (0, 1)
    tv.advance(0)
    assert tv.allowed() == (1,)
    with pytest.raises(ValueError):
        tv.advance(0)
    tv.advance(1)
    assert tv.state == "A"
    tv.advance(3)
    assert tv.state == "A"


def test_forecast_extrapolates_forwards() -> None:
    recent = np.arange(7.0)[:, None] * np.array([[1.0, -2.0]])  # constant velocity (1, -2)
    ahead = forecast(recent, 3, "euclidean")
    np.testing.assert_allclose(ahead, [[7.0, -14.0], [8.0, -16.0], [9.0, -18.0]])


def test_quaternion_forecast_keeps_a_constant_rotation_speed() -> None:
    angles = 0.1 * np.arange(6)
    q = quat.from_axis_angle("y", angles)  # (6, 4), one joint
    ahead = forecast(q, 2, "geodesic")
    expected = quat.from_axis_angle("y", np.array([0.6, 0.7]))
    np.testing.assert_allclose(np.abs(np.einsum("kc,kc->k", ahead, expected)), 1.0, atol=1e-12)


def brute_reverse(C: np.ndarray) -> np.ndarray:
    R, W = C.shape
    best = np.full((R, W), np.inf)

    def walk(i: int, j: int) -> float:
        if j == W - 1:
            return C[i, j]
        options = [walk(i, j + 1)]
        if i + 1 < R:
            options += [walk(i + 1, j), walk(i + 1, j + 1)]
        return C[i, j] + min(options)

    for i in range(R):
        for j in range(W):
            best[i, j] = walk(i, j)
    return best


def test_reverse_accumulation_with_free_end_matches_brute_force() -> None:
    C = np.random.default_rng(4).random((4, 5))
    np.testing.assert_allclose(reverse_accumulate(C, False), brute_reverse(C), rtol=1e-12)
    # with path-length weighting, D / L is the mean cost of the chosen path: never above the max
    mean = reverse_accumulate(C, True)
    assert np.all(mean <= C.max() + 1e-12) and np.all(mean >= C.min() - 1e-12)


def test_method_b_reads_the_newest_frame_off_the_path() -> None:
    # columns: previous frame, newest frame, forecast; rows: reference frames from the last match
    C = np.ones((4, 4))
    C[0, 0] = C[1, 0] = 0.0  # the previous frame also matches the next reference frame
    C[2, 1] = C[3, 2] = C[3, 3] = 0.0  # cheap path: the newest frame at row 2
    C[1, 1] = 0.5
    assert method_b_step(C) == 2
    C[1, 0] = 1.0  # now the walk climbs column 1 to its lowest row before (0, 0)
    assert method_b_step(C) == 0


def test_forward_plot_quaternion_costs_follow_the_reference() -> None:
    angles = np.linspace(0.0, 2.0, 80)
    ref = np.concatenate(
        [quat.from_axis_angle("x", angles), quat.from_axis_angle("z", angles / 2)], 1
    )
    fa = ForwardPlotAligner(
        ref, ForwardPlotOptions(window=10), DTWOptions(cost="geodesic", step="type-v")
    )
    mapping = [fa.push(f) for f in ref[np.repeat(np.arange(80), 2)]]  # twice as slow
    assert mapping[-1] >= 75 and np.all(np.diff(mapping) >= 0)
    assert cost_matrix(ref[:1], ref[:1], "geodesic")[0, 0] == 0.0


def test_forward_plot_options_are_validated() -> None:
    with pytest.raises(ValueError):
        ForwardPlotOptions(method="D")  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        ForwardPlotOptions(window=1)


def test_compiled_quaternion_forecast_equals_the_numpy_one() -> None:
    from analysis.online.aligners import forecast_reference

    rng = np.random.default_rng(3)
    for trial in range(10):
        q = quat.normalize(rng.standard_normal((7, 5, 4)))
        q = quat.make_continuous(q) if trial % 2 else q  # and frames in opposite hemispheres
        recent = q.reshape(7, -1)
        ahead = forecast(recent, 13, "quaternion")
        np.testing.assert_allclose(ahead, forecast_reference(recent, 13), atol=1e-10)
    still = np.tile(quat.normalize(rng.standard_normal((1, 3, 4))).reshape(1, -1), (4, 1))
    np.testing.assert_allclose(forecast(still, 3, "quaternion"), np.tile(still[:1], (3, 1)))
