"""One live session's on-line alignment: where the patient is in the tutor's movement, a tutor
playback kept in step, and each repetition's score and guidance the moment it ends.

Per frame (O(m) work, m the tutor repetition's length):

- WOOE-DTW (paper 000): `OpenEndAligner` with path-length weighting and the model's joint weights
  (when it has them), quaternion frame cost: the patient's place in the tutor's repetition.
- FP-C with the Type V constraint (paper 003, ch. 5-6): `ForwardPlotAligner`, window a third of
  the repetition: the tutor playback frame, which never goes back within a repetition.
- Repetition ends: `RepetitionCounter` applies the offline segmenter's rules to the progress
  along the tutor's movement axis, a fraction of a second behind the newest frame (the
  look-ahead its filters need), so the live count is the count the offline analysis gives.
  Each repetition is then aligned with the tutor's gesture by GB-DTW (paper 001: its score and
  Table 1's guidance, ``gesture_guidance``), scored by the exercise model's scorer and given
  the guidance the offline pipeline gives (``guidance``: Table 1 on the repetition's WOOE-DTW
  alignment with a tutor repetition, `analysis.pipeline.gestures`) and judged by the offline
  judgement (`analysis.live.judged`: ``passed``, the guidance kept, ``reasons``), so a patient
  hears live what the recording's page later says; ``words``: what the page shows and speaks
  (`repetition_words`: its first reason, praise only when passed without one).

Frames are the recording's own BVH channel values; joints are mapped onto the model's once, and
a stream faster than the model's frame rate is thinned to it (slower streams are used as is).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from analysis.bvh import Skeleton, map_joints
from analysis.dtw import DTWOptions
from analysis.kinematics import positions
from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import UP_AXIS
from analysis.live.frame_kernels import MIRROR_Q, FeatureLayout, FrameStore
from analysis.live.judged import RepetitionJudge, guidance_events
from analysis.live.tutor import tutor_of
from analysis.live.words import Event, repetition_words
from analysis.online.aligners import ForwardPlotAligner, ForwardPlotOptions, OpenEndAligner
from analysis.online.counting import Counted, RepetitionCounter
from analysis.online.frames import FrameKinematics
from analysis.online.gbdtw import GBDTWOptions, _gesture
from analysis.pipeline.gestures import (
    Pace,
    align_gesture,
    guidance,
    repetition_pace,
    usual_pace,
)
from analysis.pipeline.model import FittedModel
from analysis.pipeline.repetition_stage import RULES
from analysis.pipeline.results import Guidance

FloatArray = npt.NDArray[np.float64]
IndexArray = npt.NDArray[np.intp]


class _StreamRows(NamedTuple):
    """Rows of a stream frame's (J, 4) rotations, each composed once from the model's joint
    order, its mirror and the aligned joints, so that a frame is gathered once per use."""

    direct: IndexArray  # the aligned joints
    flipped: IndexArray  # their mirror images
    gesture: IndexArray  # the joints guidance aligns
    gesture_mirror: IndexArray


@dataclass(frozen=True)
class LiveOptions:
    """relative_error: GB-DTW's delta (001: 5 %); window_share: FP-C window as a share of the
    tutor repetition (003: a third of the cycle); own_pace: the patient's usual pace from earlier
    sessions (None: the session's repetitions so far), as offline."""

    relative_error: float = 0.05
    window_share: float = 1.0 / 3.0
    own_pace: Pace | None = None


class LiveAligner:
    """``push(values) -> events`` for one stream of BVH frames against an exercise model.

    skeleton: the stream's BVH skeleton (its joints are mapped onto the model's; raises
    `SkeletonMismatchError` when impossible). fps: the stream's frame rate.
    """

    def __init__(
        self,
        model: FittedModel,
        skeleton: Skeleton,
        fps: float,
        options: LiveOptions | None = None,
    ) -> None:
        self.model, self.options = model, options or LiveOptions()
        mapping = map_joints(model.joint_names, skeleton.names)
        # index arrays, not lists: numpy turns a list into an array on every use, per frame
        self._index = np.array(
            [skeleton.names.index(mapping[n]) for n in model.joint_names], dtype=np.intp
        )
        self._mirror = np.asarray(model.components.mirror, dtype=np.intp)
        self._kinematics = FrameKinematics(skeleton)
        self.n_channels = skeleton.n_channels  # values per stream frame
        self._parents = skeleton.parents
        self._period = max(1.0, fps / model.fps)  # stream frames per model frame
        self._due = 0.0
        self._setup_tutor()
        self._setup_aligners()
        self._judge = RepetitionJudge(model, skeleton)
        self.frames = 0  # stream frames pushed
        self.repetitions: list[Event] = []
        self.latencies_ms: list[float] = []
        self._place = self._playback = 0
        self._frame_of: list[int] = []  # model-rate frame -> stream frame
        self._progress: tuple[list[float], list[float]] = ([], [])  # as performed, mirrored
        gesture = np.asarray(model.components.papers.joint_index, dtype=np.intp)
        index, mirror, joints = self._index, self._mirror, self._joints
        self._rows = _StreamRows(
            index[joints], index[mirror[joints]], index[gesture], index[mirror[gesture]]
        )
        kin, axis = self._kinematics, model.components.axis
        layout = FeatureLayout(
            kin.columns, kin.axes, kin.layout, kin.offsets, kin.parents, index, mirror,
            np.ascontiguousarray(axis.start_pose, dtype=np.float64),
            np.ascontiguousarray(axis.direction, dtype=np.float64), *self._rows,
        )  # fmt: skip
        self._axis_scale = float(axis.scale)
        self._store = FrameStore(layout, len(model.joint_names))
        self._paces: list[Pace] = []  # the repetitions' so far (the patient's own pace)
        # repetitions are counted on the side the patient uses (mirror image: side 1)
        self._counter = RepetitionCounter(model.components.axis.rep_frames)
        self._side = 0
        self._span = [(np.inf, -np.inf), (np.inf, -np.inf)]  # least, most progress per side
        self._undo = np.eye(3)
        self._heading: float | None = None
        self._scale = 1.0
        self._tutor_pos: FloatArray | None = None

    # --- set-up -------------------------------------------------------------------------------

    def _setup_tutor(self) -> None:
        tutor = tutor_of(self.model)
        self._joints, self._tutor_q, self._weights = tutor.joints, tutor.q, tutor.weights
        self.tutor_start, self.tutor_end = tutor.start, tutor.end
        self._reference, self._reference_frames = tutor.reference, tutor.reference_frames

    def _setup_aligners(self) -> None:
        m = self._tutor_q.shape[0]
        self._wooe = DTWOptions(
            cost="quaternion", weights=self._weights, path_length_weighting=True
        )
        self._fp_dtw = DTWOptions(cost="quaternion", weights=self._weights, step="type-v")
        self._fp_options = ForwardPlotOptions(
            method="C", window=max(4, round(m * self.options.window_share))
        )
        self._gb = GBDTWOptions(
            relative_error=self.options.relative_error,
            dtw=DTWOptions(cost="quaternion", weights=self._weights),
        )
        self._restart_playback()

    def _restart_playback(self) -> None:
        self._oe = OpenEndAligner(self._tutor_q, self._wooe, keep_path=False)
        self._fp = ForwardPlotAligner(self._tutor_q, self._fp_options, self._fp_dtw)

    # --- per frame ----------------------------------------------------------------------------

    def push(self, values: npt.ArrayLike) -> list[Event]:
        """Add one stream frame (its C channel values); return the events it produced."""
        seq = self.frames
        self.frames += 1
        if seq < self._due:  # thinned to the model's frame rate: nothing to time or answer
            return []
        started, cpu = time.perf_counter(), time.thread_time()
        self._due += self._period
        row = np.ascontiguousarray(values, dtype=np.float64)
        q = self._features(row)
        self._judge.add(row)
        self._frame_of.append(seq)
        if self._choose_side():
            self._restart_playback()
        ended = self._counter.push(self._progress[self._side][-1])
        events = [self._repetition(c, self._side) for c in ended]
        if events:
            self._restart_playback()
        self._place = self._oe.push_finite(q[self._side][None])
        self._playback = self._fp.push(q[self._side])
        ms = (time.perf_counter() - started) * 1000.0
        self.latencies_ms.append(ms)
        event = self.position(seq, ms)
        # the processor time this thread spent on the frame: what the frame costs, whatever
        # else the machine is doing (wall time also counts waiting for a processor)
        event["cpu_ms"] = round((time.thread_time() - cpu) * 1000.0, 3)
        return [*events, event]

    def position(self, seq: int, ms: float) -> Event:
        """The position event of stream frame ``seq`` (tutor frames are the tutor file's)."""
        return {
            "event": "position",
            "frame": seq,
            "tutor_frame": self.tutor_start + self._playback,
            "place": self.tutor_start + self._place,
            "repetitions": len(self.repetitions),
            "progress": round(self._progress[self._side][-1], 3),
            "latency_ms": round(ms, 3),
        }

    def finish(self) -> list[Event]:
        """End of stream: the repetitions the look-ahead still held, then the summary."""
        found = [self._repetition(c, self._side) for c in self._counter.finish()]
        return [*found, self.summary()]

    def summary(self) -> Event:
        lat = self.latencies_ms
        return {
            "event": "summary",
            "repetitions": len(self.repetitions),
            "frames": self.frames,
            "latency_ms_p95": round(float(np.percentile(lat, 95)), 3) if lat else 0.0,
            "score": round(float(np.mean([r["score"] for r in self.repetitions])), 2)
            if self.repetitions
            else None,
            "recording": None,
        }

    def poses(self) -> tuple[FloatArray, FloatArray] | None:
        """World positions (J, 3) of the newest frame and of the tutor playback frame, in the
        model's joint order, each moved so that its root stands at x = z = 0 (for display)."""
        if self._store.t == 0:
            return None
        if self._tutor_pos is None:
            self._tutor_pos = positions(self.model.tutor)
        tutor = self._tutor_pos[self.tutor_start + self._playback]
        return _grounded(self._store.model_pos), _grounded(tutor)

    def _choose_side(self) -> bool:
        """As the offline pipeline: the mirror image when it moves 25 % more along the tutor's
        axis (so far). True when the side changed."""
        spans = [high - low for low, high in self._span]
        side = 1 if spans[1] > 1.25 * spans[0] else 0
        changed, self._side = side != self._side, side
        if changed:  # count on the new side from the start: its repetitions so far are known
            self._counter = RepetitionCounter(self.model.components.axis.rep_frames)
            for value in self._progress[side][:-1]:
                self._counter.push(value)
        return changed

    def _features(self, values: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Quaternions of the aligned joints (flat) as performed and mirrored; appends the
        progress along the tutor's axis of both."""
        if self._heading is None:
            self._face(values)
        # positions facing the first frame's heading, as performed and as `mirrored` (left and
        # right swap, x turns), their progress, the rotations compared (and those offline
        # guidance aligns, as performed whichever side is used): one compiled call
        t, store = self._store.t, self._store
        for side, value in enumerate(store.add(values, self._undo, self._axis_scale)):
            self._progress[side].append(value)
            low, high = self._span[side]
            self._span[side] = (min(low, value), max(high, value))
        return store.q[0, t], store.q[1, t]

    def _face(self, values: FloatArray) -> None:
        """From the first frame: the turn that faces its heading, over the body's size."""
        rot = self._kinematics.rotations(values[None])
        pos = self._kinematics.positions(values[None])[0]
        self._heading = float(quat.twist_angle(rot[0, :1], "XYZ"[UP_AXIS])[0])
        child = np.flatnonzero(self._parents >= 0)
        bones = np.linalg.norm(pos[child] - pos[self._parents[child]], axis=-1).sum()
        self._scale = float(bones) if bones > 1e-9 else 1.0
        undo = quat.from_axis_angle("XYZ"[UP_AXIS], -self._heading)
        # rows are the turned unit vectors, so turning row vectors p is p @ self._undo
        self._undo = np.ascontiguousarray(quat.rotate(undo, np.eye(3)) / self._scale)

    def _joint_quaternions(self, rot: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(F, d) quaternion features of the aligned joints from (F, J, 4) stream rotations, as
        performed and mirrored (each joint's mirror image)."""
        n = rot.shape[0]
        direct = rot[:, self._rows.direct].reshape(n, -1)
        return direct, (rot[:, self._rows.flipped] * MIRROR_Q).reshape(n, -1)

    def features_of(self, frames: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """The features the aligners compare for whole (F, C) stream frames, as performed and
        mirrored (for checking the live alignment against offline DTW)."""
        return self._joint_quaternions(self._kinematics.rotations(np.asarray(frames, np.float64)))

    @property
    def tutor_features(self) -> FloatArray:
        """(m, d) features of the tutor repetition the stream is aligned with."""
        return self._tutor_q

    @property
    def dtw_options(self) -> DTWOptions:
        """The frame cost and joint weights of the live alignment (for an offline reference)."""
        return DTWOptions(cost="quaternion", weights=self._weights)

    # --- repetitions --------------------------------------------------------------------------

    def _repetition(self, counted: Counted, side: int) -> Event:
        """Model-rate frames counted.start..end as a repetition event: GB-DTW against the
        tutor's gesture, the model's score, guidance."""
        a, b = counted.start, min(counted.end, len(self._frame_of) - 1)
        progress = np.asarray(self._progress[side][a : b + 1])
        reach = float(progress.max() - progress[0])
        start, end = self._frame_of[a], self._frame_of[b]
        tempo = (b - a + 1) / self._reference_frames  # as offline: the tutor's median repetition
        user = self._store.q[side, a : b + 1].copy()
        gesture = _gesture(self._tutor_q, user, user, index=len(self.repetitions), a0=0, u0=a,
                           opt=self._gb)  # fmt: skip
        score = round(self._judge.score(a, b, bool(side), self._index), 2)
        number = len(self.repetitions) + 1
        found = self._guidance(a, b, len(self.repetitions))
        self._judge.set_side(bool(side))
        verdict = self._judge.judge(
            a, b, number, score, found, reach, round(tempo, 3), self.options.own_pace
        )
        event = {
            "event": "repetition",
            "index": number - 1,
            "start": start,
            "end": end,
            "score": score,
            "passed": verdict.passed,
            "guidance": guidance_events(
                found, verdict, [self._frame_of[min(b, a + f)] for f in range(b - a + 1)]
            ),
            "reasons": list(verdict.reasons),
            "gesture_guidance": list(gesture.guidance),
            "reach": round(reach, 3),
            "tempo": round(tempo, 3),
        }
        event["words"] = repetition_words(event)
        self.repetitions.append(event)
        return event

    def _guidance(self, a: int, b: int, index: int) -> tuple[Guidance, ...]:
        """Table 1's guidance for model-rate frames a..b, by the offline pipeline's own rule
        (`analysis.pipeline.gestures.guidance` on the repetition's WOOE-DTW alignment with a
        tutor repetition, its tempo and reach against the reference's and the patient's own),
        most pressing first, with the stream frames it concerns."""
        parts = self.model.components
        papers, step = parts.papers, parts.scoring_step
        reps = parts.tutor_reps or [(self.tutor_start, self.tutor_end)]
        t0, t1 = reps[index % len(reps)]  # offline's choice when no key pose pairs them
        patient_q = self._store.gesture[0, a : b + 1 : step].copy()
        aligned = align_gesture(papers.tutor_q[t0 : t1 + 1 : step], patient_q, papers.joint_weights)
        mirror_q = self._store.gesture[1, a : b + 1 : step].copy()
        tempo = (b - a + 1) / self._reference_frames
        pace, series = repetition_pace(patient_q, mirror_q, self._reference, tempo)
        self._paces.append(pace)
        own = self.options.own_pace or usual_pace(self._paces)
        found = guidance(aligned, series, pace, own, RULES)
        return tuple(Guidance(g.type, (step * g.frames[0], step * g.frames[1])) for g in found)


def _grounded(points: FloatArray) -> FloatArray:
    out = points.copy()
    out[:, [0, 2]] -= points[0, [0, 2]]
    return out


def rehearse(model: FittedModel) -> int:
    """Stream the tutor's own recording once through a `LiveAligner` and return its count, so
    that a server process loads the modules and compiled kernels of every live step (repetition
    scoring included) before its first session's frames wait for them."""
    tutor = model.tutor
    aligner = LiveAligner(model, tutor.skeleton, tutor.fps)
    for values in tutor.frames:
        aligner.push(values)
    return int(aligner.finish()[-1]["repetitions"])
