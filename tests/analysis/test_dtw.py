"""DTW: properties of the paths, exactness of the compiled fast paths against the reference."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analysis.dtw import offline as dtw
from analysis.dtw import row_blocks
from analysis.dtw.frame_costs import CostKind, cost_matrix, frame_cost
from analysis.dtw.offline import Alignment, DTWOptions, align, band_limits, distance
from tests import dtw_reference

KINDS = ("euclidean", "sqeuclidean", "quaternion", "geodesic")


def unit_quaternions(rng: np.random.Generator, n: int, joints: int) -> np.ndarray:
    q = rng.standard_normal((n, joints, 4))
    return (q / np.linalg.norm(q, axis=-1, keepdims=True)).reshape(n, 4 * joints)


def frames(rng: np.random.Generator, kind: str, n: int, d: int) -> np.ndarray:
    if kind in ("quaternion", "geodesic"):
        return unit_quaternions(rng, n, max(1, d // 4))
    return rng.standard_normal((n, d))


def assert_same(fast: Alignment, ref: Alignment) -> None:
    assert fast.cost == pytest.approx(ref.cost, rel=1e-9, abs=1e-12)
    np.testing.assert_array_equal(fast.path, ref.path)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("d", [1, 8, 24])
def test_identical_inputs_cost_zero_on_the_diagonal(kind: str, d: int) -> None:
    x = frames(np.random.default_rng(d), kind, 40, d)
    a = align(x, x, DTWOptions(cost=kind))
    assert a.cost == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_array_equal(a.path, np.stack([np.arange(40)] * 2, axis=1))
    assert distance(x, x, DTWOptions(cost=kind)) == pytest.approx(0.0, abs=1e-9)


def test_many_features_keep_exact_zeros() -> None:
    # differences are taken feature by feature (no |x|^2 + |y|^2 - 2xy expansion, which cancels):
    # identical frames cost exactly nothing, through the four-row kernel and its remainder rows
    x = np.random.default_rng(0).standard_normal((50, 66)) * 100.0
    assert distance(x, x) == 0.0
    assert align(x, x).cost == 0.0


def is_symmetric_path(path: np.ndarray) -> bool:
    steps = np.diff(path, axis=0)
    allowed = {(1, 0), (0, 1), (1, 1)}
    return all(tuple(s) in allowed for s in steps)


@pytest.mark.parametrize(
    "opt",
    [
        DTWOptions(),
        DTWOptions(window=5),
        DTWOptions(path_length_weighting=True),
        DTWOptions(open_end=True),
        DTWOptions(open_begin=True, open_end=True),
    ],
)
def test_path_is_monotonic_and_continuous(opt: DTWOptions) -> None:
    rng = np.random.default_rng(1)
    x, y = rng.standard_normal((37, 3)), rng.standard_normal((52, 3))
    path = align(x, y, opt).path
    assert is_symmetric_path(path)
    assert path[0, 0] == 0 and path[-1, 0] == len(x) - 1
    if not opt.open_begin:
        assert path[0, 1] == 0
    if not opt.open_end:
        assert path[-1, 1] == len(y) - 1


def test_type_v_path_steps() -> None:
    rng = np.random.default_rng(2)
    x, y = rng.standard_normal((60, 2)), rng.standard_normal((45, 2))
    path = align(x, y, DTWOptions(step="type-v")).path
    di, dj = np.diff(path, axis=0).T
    assert np.all(di == 1) and set(dj) <= {0, 1, 2, 3}
    repeats = "".join("0" if s == 0 else "x" for s in dj)
    assert "000" not in repeats  # never more than two repeated reference frames in a row
    assert tuple(path[-1]) == (59, 44)


def test_known_time_warp_is_recovered() -> None:
    t = np.linspace(0.0, 1.0, 300)
    signal = np.stack([np.sin(6 * np.pi * t), np.cos(4 * np.pi * t**2)], axis=1)
    u = np.linspace(0.0, 1.0, 360)
    warp = u + 0.15 * np.sin(2 * np.pi * u) / (2 * np.pi)  # monotonic, fixed end points
    warped = np.stack([np.interp(warp, t, signal[:, k]) for k in range(2)], axis=1)
    path = align(warped, signal).path
    truth = warp * (len(t) - 1)
    error = np.abs(path[:, 1] - truth[path[:, 0]])
    assert np.median(error) <= 1.0 and error.max() <= 4.0


def test_small_example_by_hand() -> None:
    x = np.array([0.0, 1.0, 2.0])
    y = np.array([0.0, 2.0])
    a = align(x, y, DTWOptions(cost="sqeuclidean"))
    # (0,0) 0 -> (1,0) 1 or (1,1) 1 -> (2,1) 0: best total 1
    assert a.cost == 1.0
    assert a.path.tolist() in ([[0, 0], [1, 0], [2, 1]], [[0, 0], [1, 1], [2, 1]])
    np.testing.assert_array_equal(
        a.path, dtw_reference.align(x, y, a_opt := DTWOptions(cost="sqeuclidean")).path
    )
    assert distance(x, y, a_opt) == 1.0


def test_band_limits_exact() -> None:
    lo, hi = band_limits(5, 9, DTWOptions(window=1))
    # |j * 4 - i * 8| <= 4  ->  j in [2i - 1, 2i + 1]
    np.testing.assert_array_equal(lo, [0, 1, 3, 5, 7])
    np.testing.assert_array_equal(hi, [1, 3, 5, 7, 8])
    lo, hi = band_limits(4, 3, DTWOptions(window=1, open_end=True))
    np.testing.assert_array_equal(lo, [0, 0, 1, 2])
    np.testing.assert_array_equal(hi, [1, 2, 2, 2])


OPTION_GRID = [
    DTWOptions(window=w, open_begin=ob, open_end=oe, path_length_weighting=plw, step=s)
    for w, ob, oe, plw, s in itertools.product(
        [None, 2], [False, True], [False, True], [False, True], ["symmetric", "type-v"]
    )
]


@settings(max_examples=60, derandomize=True, deadline=None)
@given(
    shape=st.tuples(st.integers(1, 12), st.integers(1, 12), st.sampled_from([1, 3, 12])),
    kind=st.sampled_from(KINDS),
    weighted=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_fast_path_equals_reference(
    shape: tuple[int, int, int], kind: str, weighted: bool, seed: int
) -> None:
    """Every option, alone and combined, on random inputs: costs to 1e-9, identical paths.

    n >= 4 runs the four-row Euclidean kernel (plus remainder rows), d <= 8 the anti-diagonal
    sweep for plain distances."""
    n, m, d = shape
    rng = np.random.default_rng(seed)
    x, y = frames(rng, kind, n, d), frames(rng, kind, m, d)
    joints = x.shape[1] // 4 if kind in ("quaternion", "geodesic") else x.shape[1]
    weights = tuple(rng.uniform(0.1, 2.0, joints)) if weighted else None
    for base in OPTION_GRID:
        for si in (False, True):
            opt = replace(
                base, cost=kind, weights=weights, speed_insensitive=si, return_matrix=True
            )
            try:
                ref = dtw_reference.align(x, y, opt)
            except ValueError:
                with pytest.raises(ValueError):
                    align(x, y, opt)
                continue
            fast = align(x, y, opt)
            assert_same(fast, ref)
            np.testing.assert_allclose(fast.matrix, ref.matrix, rtol=1e-12, atol=1e-12)
            plain = replace(opt, return_matrix=False)
            assert distance(x, y, plain) == pytest.approx(ref.cost, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("kind", ["euclidean", "sqeuclidean"])
@pytest.mark.parametrize("d", [1, 3, 8])
def test_antidiagonal_path_equals_row_sweep(kind: str, d: int) -> None:
    """The anti-diagonal sweep (closed, unbanded, few features) gives the row sweep's cost and
    path bit for bit, ties included (small integer frames tie often); a window wider than the
    inputs keeps the same band but sends the work to the row sweep."""
    rng = np.random.default_rng(11 + d)
    for trial in range(40):
        n, m = (int(v) for v in rng.integers(1, 30, 2))
        if trial % 2:
            x, y = rng.integers(0, 3, (n, d)).astype(float), rng.integers(0, 3, (m, d)) * 1.0
        else:
            x, y = rng.standard_normal((n, d)), rng.standard_normal((m, d))
        for si in (False, True):
            opt = DTWOptions(cost=kind, speed_insensitive=si)
            rows = align(x, y, replace(opt, window=100))
            fast = align(x, y, opt)
            assert fast.cost == rows.cost
            np.testing.assert_array_equal(fast.path, rows.path)
            assert_same(fast, dtw_reference.align(x, y, opt))
        plain = DTWOptions(cost=kind)
        assert distance(x, y, plain) == align(x, y, replace(plain, window=100)).cost


def test_blocked_pipeline_equals_reference(monkeypatch: pytest.MonkeyPatch) -> None:
    # Tiny blocks force many cost blocks, the second thread and the block seams.
    monkeypatch.setattr(row_blocks, "BLOCK_CELLS", 40)
    rng = np.random.default_rng(3)
    for d in (2, 12):
        x, y = rng.standard_normal((23, d)), rng.standard_normal((17, d))
        for opt in (
            DTWOptions(),
            DTWOptions(path_length_weighting=True, window=4),
            DTWOptions(step="type-v", open_end=True),
        ):
            assert_same(align(x, y, opt), dtw_reference.align(x, y, opt))
            assert distance(x, y, opt) == pytest.approx(
                dtw_reference.align(x, y, opt).cost, rel=1e-9
            )


@pytest.mark.parametrize("opt", [*OPTION_GRID[::3], DTWOptions(speed_insensitive=True)])
def test_batch_equals_single(opt: DTWOptions) -> None:
    rng = np.random.default_rng(4)
    y = rng.standard_normal((14, 12))
    xs = [rng.standard_normal((k, 12)) for k in (9, 14, 20, 11)]
    try:
        singles = [align(x, y, opt) for x in xs]
    except ValueError:
        with pytest.raises(ValueError):
            dtw.align_batch(xs, y, opt)
        return
    batch = dtw.align_batch(xs, y, opt)
    for s, b in zip(singles, batch, strict=True):
        assert_same(b, s)
    np.testing.assert_allclose(
        dtw.distance_batch(xs, y, opt), [s.cost for s in singles], rtol=1e-12
    )


@pytest.mark.parametrize("kind", ["euclidean", "sqeuclidean"])
def test_pruned_batch_equals_reference(kind: CostKind) -> None:
    """Repetitions close to the reference (most cells pruned), unrelated ones (few pruned),
    integer frames (ties), per-feature weights and bands; a band the corner-to-corner path
    leaves (nothing pruned), and one with no admissible path at all."""
    rng = np.random.default_rng(12)
    y = rng.standard_normal((40, 18))
    xs = [
        y + 0.3 * rng.standard_normal(y.shape),
        np.repeat(y, 2, axis=0)[::3] + 0.1 * rng.standard_normal((27, 18)),
        rng.standard_normal((55, 18)),
        rng.integers(0, 2, (33, 18)).astype(float),
        y[:1],
    ]
    for opt in (
        DTWOptions(cost=kind),
        DTWOptions(cost=kind, weights=tuple(rng.uniform(0.2, 2.0, 6)), window=5),
        DTWOptions(cost=kind, window=0),
    ):
        ref = []
        for x in xs:
            try:
                ref.append(dtw_reference.align(x, y, opt).cost)
            except ValueError:
                ref.append(None)
        if None in ref:
            with pytest.raises(ValueError, match="no admissible"):
                dtw.distance_batch(xs, y, opt)
            usable = [x for x, r in zip(xs, ref, strict=True) if r is not None]
            ref = [r for r in ref if r is not None]
        else:
            usable = xs
        np.testing.assert_allclose(dtw.distance_batch(usable, y, opt), ref, rtol=1e-12)


def test_path_rows_equal_general_rows() -> None:
    """The closed-begin path DP (no range tests) gives the general row's values and
    back-pointers, band edges and ties (integer frames) included."""
    rng = np.random.default_rng(13)
    for trial in range(30):
        n, m = (int(v) for v in rng.integers(1, 25, 2))
        x, y = rng.integers(0, 3, (n, 2)).astype(float), rng.integers(0, 3, (m, 2)) * 1.0
        C = cost_matrix(x, y, "sqeuclidean")
        window = None if trial % 3 == 0 else int(rng.integers(0, 6))
        lo, hi = band_limits(n, m, DTWOptions(window=window, open_end=trial % 2 == 1))
        fast, general = (
            dtw.DPState(n, m, DTWOptions(), path=True),
            dtw.DPState(n, m, DTWOptions(), path=True),
        )
        general.path_only = False
        fast.rows(C, 0, n, lo, hi)
        general.rows(C, 0, n, lo, hi)
        assert fast.path_only
        rows = [i for i in range(n) if lo[i] <= hi[i]]
        for i in rows:
            np.testing.assert_array_equal(
                fast.dirs[i, lo[i] : hi[i] + 1], general.dirs[i, lo[i] : hi[i] + 1]
            )
        last = (n - 1) & 1
        np.testing.assert_array_equal(
            fast.D[last, lo[n - 1] : hi[n - 1] + 1], general.D[last, lo[n - 1] : hi[n - 1] + 1]
        )


def test_batch_uses_two_threads_on_big_batches(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(row_blocks, "PARALLEL_MIN_CELLS", 0)
    rng = np.random.default_rng(5)
    y = rng.standard_normal((30, 4))
    xs = [rng.standard_normal((25, 4)) for _ in range(7)]
    np.testing.assert_allclose(dtw.distance_batch(xs, y), [distance(x, y) for x in xs], rtol=1e-12)


def test_speed_insensitive_counts_a_slow_stretch_once() -> None:
    y = np.array([0.0, 1.0, 2.0])
    x = np.array([0.0, 1.0, 1.0, 1.0, 2.0])
    slow = align(x, y)
    assert slow.cost == 0.0
    # one tutor frame matched by three user frames: eq 17 averages them, still 0
    assert align(x, y, DTWOptions(speed_insensitive=True)).cost == 0.0
    x2 = np.array([0.0, 0.8, 1.2, 2.0])
    plain = align(x2, y).cost
    insensitive = align(x2, y, DTWOptions(speed_insensitive=True)).cost
    assert insensitive < plain  # 0.8 and 1.2 average to 1.0


def test_frame_cost_formulas() -> None:
    q = np.array([1.0, 0.0, 0.0, 0.0])
    r = np.array([np.cos(0.5), np.sin(0.5), 0.0, 0.0])  # 1 radian about x
    assert frame_cost(q, r, "quaternion") == pytest.approx(1 - np.cos(0.5))
    assert frame_cost(q, r, "geodesic") == pytest.approx(2 / np.pi * 0.5)
    assert frame_cost(q, -r, "geodesic") == pytest.approx(2 / np.pi * 0.5)  # q and -q agree
    a, b = np.array([0.0, 0.0, 3.0]), np.array([4.0, 0.0, 0.0])
    assert frame_cost(a, b, "euclidean") == 5.0
    assert frame_cost(a, b, "euclidean", weights=[1.0, 5.0, 0.0]) == pytest.approx(4.0)
    C = cost_matrix(a[None], b[None], "sqeuclidean")
    assert C[0, 0] == 25.0


def test_per_joint_weights_group_features() -> None:
    rng = np.random.default_rng(6)
    x, y = rng.standard_normal((5, 6)), rng.standard_normal((4, 6))
    w = [2.0, 0.5, 1.0]  # three joints of two features each
    C = cost_matrix(x, y, "euclidean", w)
    wf = np.repeat(w, 2)
    expected = np.sqrt((((x[:, None] - y[None]) ** 2) * wf).sum(-1))
    np.testing.assert_allclose(C, expected, rtol=1e-12)


def test_invalid_inputs_raise() -> None:
    x = np.zeros((5, 3))
    with pytest.raises(ValueError, match="features"):
        align(x, np.zeros((5, 2)))
    with pytest.raises(ValueError, match="NaN"):
        align(np.full((3, 3), np.nan), x)
    with pytest.raises(ValueError):
        DTWOptions(cost="manhattan")  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        DTWOptions(window=-1)
    with pytest.raises(ValueError):
        align(x, x, DTWOptions(weights=(1.0, 1.0)))
    with pytest.raises(ValueError, match="quaternion"):
        align(x, x, DTWOptions(cost="quaternion"))
    with pytest.raises(ValueError, match="no admissible"):
        align(np.zeros((2, 1)), np.zeros((9, 1)), DTWOptions(step="type-v"))


def test_result_is_frozen() -> None:
    a = align(np.arange(4.0), np.arange(5.0))
    with pytest.raises(AttributeError):
        a.cost = 1.0  # type: ignore[misc]
    with pytest.raises(ValueError):
        a.path[0, 0] = 3
    assert a.matrix is None
    assert align(np.arange(4.0), np.arange(5.0), DTWOptions(return_matrix=True)).matrix.shape == (
        4,
        5,
    )


@pytest.mark.parametrize("kind", ["euclidean", "sqeuclidean"])
def test_matrix_product_costs_equal_reference(kind: str) -> None:
    """The BLAS expansion (d >= 16, blocks of >= 8 rows) stays within 1e-9 of the reference,
    also where it cancels: large offsets, near-identical and identical frames."""
    rng = np.random.default_rng(7)
    y = 1000.0 + rng.standard_normal((26, 24))
    x = np.concatenate([y[:10] + 1e-7 * rng.standard_normal((10, 24)), y[5:15], y[::-2]])
    weights = tuple(rng.uniform(0.5, 2.0, 6))
    for opt in (
        DTWOptions(cost=kind),
        DTWOptions(cost=kind, weights=weights, window=6, path_length_weighting=True),
        DTWOptions(cost=kind, open_begin=True, open_end=True, step="type-v"),
    ):
        ref = dtw_reference.align(x, y, opt)
        assert distance(x, y, opt) == pytest.approx(ref.cost, rel=1e-9, abs=1e-12)
        assert align(x, y, opt).cost == pytest.approx(ref.cost, rel=1e-9, abs=1e-12)
        assert dtw.distance_batch([x, x[3:]], y, opt)[0] == pytest.approx(ref.cost, rel=1e-9)
    C = cost_matrix(x, y, kind, weights)
    exact = np.array([[frame_cost(a, b, kind, weights) for b in y] for a in x])
    np.testing.assert_allclose(C, exact, rtol=1e-10, atol=0)
    assert np.all(C[10:20, 5:15].diagonal() == 0.0)  # identical frames: exactly zero


def test_blas_limit_is_counted_and_restored() -> None:
    from threadpoolctl import threadpool_info

    from analysis.dtw.cost_blas import single_threaded_blas

    def blas_threads() -> list[int]:
        return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]

    before = blas_threads()
    with single_threaded_blas():
        with single_threaded_blas():
            assert all(t == 1 for t in blas_threads())
        assert all(t == 1 for t in blas_threads())  # the inner exit does not undo the outer
    assert blas_threads() == before
