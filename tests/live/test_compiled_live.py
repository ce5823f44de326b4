"""The live aligner's compiled per-frame path gives the events of the numpy and Python-object
path it replaced, exactly: UI-PRMD sessions (data/ui-prmd, the repository's copy) streamed
frame by frame through both, every event's every field equal but the timings (issue 37)."""

from __future__ import annotations

from typing import Literal

import numpy as np
import pytest
from scipy.signal import find_peaks

from analysis.bvh import Motion, read
from analysis.dtw import DTWOptions, cost_rows
from analysis.dtw import kernels as kern
from analysis.kinematics import quaternions as quat
from analysis.kinematics import resample
from analysis.kinematics.forward_kinematics import UP_AXIS
from analysis.landmarks.segmentation import MIN_PROMINENCE
from analysis.live import LiveAligner
from analysis.live.frame_kernels import MIRROR_X
from analysis.online.aligners import ForwardPlotAligner, ForwardPlotOptions, OpenEndAligner
from analysis.online.peaks import percentile, prominent_peaks
from analysis.pipeline import FittedModel
from tests.personas import FIXTURES

TIMINGS = {"latency_ms", "cpu_ms", "latency_ms_p95"}


class ObjectPathAligner(LiveAligner):
    """The per-frame path before it was compiled: features by numpy from the frame's rotations
    and positions, the open-end aligner's checked ``push``, FP-C's step by numpy and the
    compiled kernels called one at a time."""

    def _features(self, values):
        rot = self._kinematics.rotations(values[None])
        pos = self._kinematics.positions(values[None])[0]
        model_pos = pos[self._index]
        if self._heading is None:
            self._heading = float(quat.twist_angle(rot[0, :1], "XYZ"[UP_AXIS])[0])
            child = np.flatnonzero(self._parents >= 0)
            bones = np.linalg.norm(pos[child] - pos[self._parents[child]], axis=-1).sum()
            self._scale = float(bones) if bones > 1e-9 else 1.0
            undo = quat.from_axis_angle("XYZ"[UP_AXIS], -self._heading)
            self._undo = quat.rotate(undo, np.eye(3)) / self._scale
        points = (model_pos - pos[0]) @ self._undo
        sides = np.stack((points, points[self._mirror] * MIRROR_X)).reshape(2, -1)
        for side, value in enumerate(self.model.components.axis.progress(sides).tolist()):
            self._progress[side].append(value)
            low, high = self._span[side]
            self._span[side] = (min(low, value), max(high, value))
        row, store, t = rot[0], self._store, self._store.t
        if t == store.q.shape[1]:
            store.q = np.concatenate([store.q, np.empty_like(store.q)], axis=1)
            store.gesture = np.concatenate([store.gesture, np.empty_like(store.gesture)], axis=1)
        store.model_pos[:] = model_pos
        store.gesture[0, t] = row[self._rows.gesture]
        store.gesture[1, t] = row[self._rows.gesture_mirror]
        direct, flipped = (q[0] for q in self._joint_quaternions(rot))
        store.q[0, t], store.q[1, t] = direct, flipped
        store.t += 1
        return direct, flipped

    def _restart_playback(self) -> None:
        super()._restart_playback()
        oe = self._oe
        oe.push_finite = lambda x: kernels_one_by_one(oe, x)  # type: ignore[method-assign]
        self._fp._compiled_c = False


def kernels_one_by_one(oe: OpenEndAligner, x: np.ndarray) -> int:
    """`OpenEndAligner.push_finite` as it was: the compiled cost row and DP row called one at a
    time from Python."""
    t = oe.t
    if t >= oe._lo.size:
        oe._grow(2 * oe._lo.size)
    oe._lo[t], oe._hi[t] = 0, oe.reference.shape[0] - 1
    ci = oe._ci.with_query(x)
    cost_rows(ci.mode, ci.x, ci.yt, ci.wj, -t, t, t + 1, oe._lo, oe._hi, oe._crow)
    head = (oe._crow, t, t + 1, oe._lo, oe._hi, bool(oe.options.open_begin))
    tail = (oe._dirs, oe._keep, oe._full, False, oe._omega, True)
    plw = bool(oe.options.path_length_weighting)
    kern.rows_symmetric(*head, plw, oe._D, oe._L, *tail)
    oe.t += 1
    return int(oe._omega[t])


def streamed(aligner: LiveAligner, motion: Motion) -> list[dict[str, object]]:
    events = [e for values in motion.frames for e in aligner.push(values)]
    events += aligner.finish()
    return [{k: v for k, v in e.items() if k not in TIMINGS} for e in events]


def session(name: str, fps: float | None = None) -> Motion:
    motion = read(FIXTURES / "sessions" / f"{name}.bvh.gz")
    return motion if fps is None else resample(motion, fps)


@pytest.mark.parametrize(
    ("name", "fps"),
    [("m07_s02_correct", None), ("m07_s03_incorrect", 120.0), ("m07_s05_incorrect", None),
     ("m07_s06_correct", 60.0)],
)  # fmt: skip
def test_compiled_path_gives_the_object_paths_events(
    live_model: FittedModel, name: str, fps: float | None
) -> None:
    motion = session(name, fps)
    compiled = streamed(LiveAligner(live_model, motion.skeleton, motion.fps), motion)
    objects = streamed(ObjectPathAligner(live_model, motion.skeleton, motion.fps), motion)
    assert compiled == objects
    kinds = [e["event"] for e in compiled]
    assert kinds.count("repetition") >= 5, "the session needs repetitions to say anything"
    playback = [e["tutor_frame"] for e in compiled if e["event"] == "position"]
    assert len(set(playback)) > 20, "the tutor playback moves"


def test_open_end_push_finite_is_push() -> None:
    rng = np.random.default_rng(3)
    reference = quat.normalize(rng.standard_normal((30, 3, 4))).reshape(30, -1)
    query = quat.normalize(rng.standard_normal((25, 3, 4))).reshape(25, -1)
    for opt in (DTWOptions(cost="quaternion", weights=(1.0, 0.5, 2.0), path_length_weighting=True),
                DTWOptions(cost="quaternion", step="type-v"), DTWOptions(window=4)):  # fmt: skip
        checked, finite = OpenEndAligner(reference, opt), OpenEndAligner(reference, opt)
        answers = [(checked.push(q), finite.push_finite(q[None].copy())) for q in query]
        assert [a for a, _ in answers] == [b for _, b in answers]
        assert np.array_equal(checked.row(), finite.row())
        assert len({a for a, _ in answers}) > 3
    with pytest.raises(ValueError, match="NaN"):
        OpenEndAligner(reference).push(np.full(12, np.nan))


@pytest.mark.parametrize("step", ["symmetric", "type-v"])
@pytest.mark.parametrize("plw", [False, True])
def test_compiled_fp_c_step_is_the_numpy_step(
    step: Literal["symmetric", "type-v"], plw: bool
) -> None:
    rng = np.random.default_rng(5)
    turns = np.cumsum(rng.normal(0.0, 0.05, (60, 4, 3)), axis=0)
    reference = quat.from_rotvec(turns).reshape(60, -1)
    query = quat.from_rotvec(turns[::2] + rng.normal(0.0, 0.01, (30, 4, 3))).reshape(30, -1)
    dtw = DTWOptions(cost="quaternion", weights=(1.0, 2.0, 0.5, 1.0), step=step,
                     path_length_weighting=plw)  # fmt: skip
    options = ForwardPlotOptions(method="C", window=12)
    compiled = ForwardPlotAligner(reference, options, dtw)
    plain = ForwardPlotAligner(reference, options, dtw)
    plain._compiled_c = False
    mapped = [(compiled.push(q), plain.push(q)) for q in query]
    assert [a for a, _ in mapped] == [b for _, b in mapped]
    assert mapped[-1][0] >= 15, "the playback follows the query through the reference"
    with pytest.raises(ValueError, match="NaN"):
        for _ in range(8):
            compiled.push(np.full(16, np.nan))


def test_compiled_peaks_are_scipys() -> None:
    """The counter's compiled peak search answers what scipy's find_peaks answers, on signals
    with plateaus, equal heights (scipy answers those) and padding."""
    rng = np.random.default_rng(11)
    for trial in range(300):
        signal = np.cumsum(rng.normal(0.0, 0.1, rng.integers(5, 200)))
        if trial % 3 == 0:  # plateaus and repeated heights
            signal = np.round(signal, 1)
        left, right, floor = int(rng.integers(0, 5)), int(rng.integers(0, 5)), signal.min() - 0.1
        distance = int(rng.integers(1, 12))
        padded = np.pad(signal, (left, right), constant_values=floor)
        peaks, props = find_peaks(padded, distance=distance, prominence=MIN_PROMINENCE)
        got = prominent_peaks(signal, left, right, float(floor), distance)
        assert got == (peaks.tolist(), props["prominences"].tolist())


def test_counters_percentile_is_numpys() -> None:
    rng = np.random.default_rng(2)
    for n in [*range(1, 300), 1000, 4000]:
        values = rng.normal(size=n) * rng.uniform(0.1, 10.0)
        if n % 5 == 0:  # repeated values
            values = np.round(values, 1)
        for q in (5.0, 50.0, 95.0):
            assert percentile(values, q) == float(np.percentile(values, q))
