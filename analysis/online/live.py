"""One live session's on-line alignment: where the patient is in the tutor's movement, a tutor
playback kept in step, and each repetition's score and guidance the moment it ends.

Per frame (O(m) work, m the tutor repetition's length):

- WOOE-DTW (paper 000): `OpenEndAligner` with path-length weighting and the model's joint weights
  (when it has them), quaternion frame cost: the patient's place in the tutor's repetition.
- FP-C with the Type V constraint (paper 003, ch. 5-6): `ForwardPlotAligner`, window a third of
  the repetition: the tutor playback frame, which never goes back within a repetition.
- GB-DTW (paper 001): `GestureStream` cuts the stream into repetitions of the tutor's first
  repetition; each one that moved far enough along the tutor's movement axis is counted, scored
  by the exercise model's scorer (as the offline pipeline does) and given guidance.

Frames are the recording's own BVH channel values; joints are mapped onto the model's once, and
a stream faster than the model's frame rate is thinned to it (slower streams are used as is).
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.signal import find_peaks

from analysis.assessment import guidance_for, repetition_features
from analysis.bvh import Motion, Skeleton, map_joints
from analysis.dtw import DTWOptions
from analysis.kinematics import flatten, positions, relative_to_start, rotations
from analysis.kinematics import quaternions as quat
from analysis.kinematics.forward_kinematics import UP_AXIS
from analysis.online.aligners import ForwardPlotAligner, ForwardPlotOptions, OpenEndAligner
from analysis.online.gbdtw import GBDTWOptions, Gesture
from analysis.online.gestures import GestureLimits, GestureStream
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import mirrored

FloatArray = npt.NDArray[np.float64]
Event = dict[str, Any]
MIN_REACH = 0.15  # tutor units along the movement axis: less is a rest, not a repetition
RELATIVE_PROMINENCE = 0.45
SPLIT_PROMINENCE = 0.3  # tutor units: two humps this distinct in one gesture are two repetitions
REST_SHARE = 0.5  # of the movement's range: a repetition ends in its lower part
MIRROR_Q = np.array([1.0, 1.0, -1.0, -1.0])  # (w, x, y, z) reflected in the lateral (x) axis
GUIDANCE_TEXT = {
    "too fast": "Slow down: take as long as the tutor.",
    "too slow": "A little faster: keep the tutor's pace.",
    "overdone": "Not so far: stop where the tutor stops.",
    "incomplete": "Go further: reach the tutor's end position.",
}


@dataclass(frozen=True)
class LiveOptions:
    """confirm_frames / relative_error: GB-DTW's e and delta (001 uses 20 and 5 %, at 30 Hz
    the e frames are scaled to the model's rate); window_share: FP-C window as a share of the
    tutor repetition (003: a third of the cycle)."""

    confirm_seconds: float = 0.35
    relative_error: float = 0.05
    window_share: float = 1.0 / 3.0
    min_reach: float = MIN_REACH


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
        self._index = [skeleton.names.index(mapping[n]) for n in model.joint_names]
        self._motion = Motion(skeleton, np.zeros((1, skeleton.n_channels)), 1.0 / fps)
        self._period = max(1.0, fps / model.fps)  # stream frames per model frame
        self._due = 0.0
        self._setup_tutor()
        self._setup_aligners()
        self.frames = 0  # stream frames pushed
        self.repetitions: list[Event] = []
        self.latencies_ms: list[float] = []
        self._place = self._playback = 0
        self._frame_of: list[int] = []  # model-rate frame -> stream frame
        self._progress: tuple[list[float], list[float]] = ([], [])  # as performed, mirrored
        self._side = 0  # 1 when the patient moves the tutor's other side (mirror image)
        self._points: list[FloatArray] = []
        self._heading: float | None = None
        self._scale = 1.0
        self._last_pos: FloatArray | None = None
        self._tutor_pos: FloatArray | None = None

    # --- set-up -------------------------------------------------------------------------------

    def _setup_tutor(self) -> None:
        parts = self.model.components
        self._joints = [j for j in parts.involved_index if j != 0] or list(parts.involved_index)
        a, b = parts.tutor_reps[0] if parts.tutor_reps else (0, self.model.tutor.n_frames - 1)
        self.tutor_start, self.tutor_end = int(a), int(b)
        q = rotations(self.model.tutor)[a : b + 1][:, self._joints]
        self._tutor_q = quat.make_continuous(q).reshape(b - a + 1, -1)
        weights = getattr(parts, "joint_weights", None)
        self._weights = None if weights is None else tuple(np.asarray(weights)[self._joints])

    def _setup_aligners(self) -> None:
        ref, m = self._tutor_q, self._tutor_q.shape[0]
        fps = self.model.fps
        self._wooe = DTWOptions(
            cost="quaternion", weights=self._weights, path_length_weighting=True
        )
        self._fp_dtw = DTWOptions(cost="quaternion", weights=self._weights, step="type-v")
        self._fp_options = ForwardPlotOptions(
            method="C", window=max(4, round(m * self.options.window_share))
        )
        gb = GBDTWOptions(
            confirm_frames=max(3, round(self.options.confirm_seconds * fps)),
            relative_error=self.options.relative_error,
            dtw=DTWOptions(cost="quaternion", weights=self._weights),
        )
        limits = GestureLimits(max(4, m // 2), 4 * m)
        self._gestures = (
            GestureStream(ref, gb, limits, lambda a, b: self._at_rest(a, b, 0)),
            GestureStream(ref, gb, limits, lambda a, b: self._at_rest(a, b, 1)),
        )
        self._restart_playback()

    def _restart_playback(self) -> None:
        self._oe = OpenEndAligner(self._tutor_q, self._wooe, keep_path=False)
        self._fp = ForwardPlotAligner(self._tutor_q, self._fp_options, self._fp_dtw)

    # --- per frame ----------------------------------------------------------------------------

    def push(self, values: npt.ArrayLike) -> list[Event]:
        """Add one stream frame (its C channel values); return the events it produced."""
        started = time.perf_counter()
        seq = self.frames
        self.frames += 1
        if seq < self._due:
            return []
        self._due += self._period
        q = self._features(np.asarray(values, dtype=np.float64))
        self._frame_of.append(seq)
        if self._choose_side():
            self._restart_playback()
        events = []
        for side in (0, 1):  # both sides are followed; the one the patient uses is counted
            ended = self._gestures[side].push(q[side])
            if side == self._side:
                events += [e for g in ended for e in self._repetitions(g, side)]
        if events:
            self._restart_playback()
        self._place = self._oe.push(q[self._side])
        self._playback = self._fp.push(q[self._side])
        ms = (time.perf_counter() - started) * 1000.0
        self.latencies_ms.append(ms)
        return [*events, self.position(seq, ms)]

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
        """End of stream: the open repetition (if it is one), then the summary."""
        last = self._gestures[self._side].finish()
        found = self._repetitions(last, self._side, final=True) if last is not None else []
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
        if self._last_pos is None:
            return None
        if self._tutor_pos is None:
            self._tutor_pos = positions(self.model.tutor)
        tutor = self._tutor_pos[self.tutor_start + self._playback]
        return _grounded(self._last_pos), _grounded(tutor)

    def _choose_side(self) -> bool:
        """As the offline pipeline: the mirror image when it moves 25 % more along the tutor's
        axis (so far). True when the side changed."""
        spans = [float(np.ptp(p)) for p in self._progress]
        side = 1 if spans[1] > 1.25 * spans[0] else 0
        changed, self._side = side != self._side, side
        return changed

    def _features(self, values: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Quaternions of the aligned joints (flat) as performed and mirrored; appends the
        progress along the tutor's axis of both."""
        motion = self._motion.with_frames(values[None])
        rot = rotations(motion)[0]
        pos = positions(motion)[0]
        self._last_pos = pos[self._index]
        if self._heading is None:
            self._heading = float(quat.twist_angle(rot[:1], "XYZ"[UP_AXIS])[0])
            parents = motion.skeleton.parents
            child = np.flatnonzero(parents >= 0)
            bones = np.linalg.norm(pos[child] - pos[parents[child]], axis=-1).sum()
            self._scale = float(bones) if bones > 1e-9 else 1.0
        undo = quat.from_axis_angle("XYZ"[UP_AXIS], -self._heading)
        points = quat.rotate(undo, pos - pos[:1])[self._index] / self._scale
        self._points.append(points)
        parts = self.model.components
        mirror = mirrored(points[None], parts.mirror)[0]
        for side, pose in enumerate((points, mirror)):
            self._progress[side].append(float(parts.axis.progress(pose.reshape(1, -1))[0]))
        local = rot[self._index]
        flipped = local[parts.mirror] * MIRROR_Q  # the mirror image of each joint's rotation
        return local[self._joints].reshape(-1), flipped[self._joints].reshape(-1)

    # --- repetitions --------------------------------------------------------------------------

    def _at_rest(self, start: int, end: int, side: int) -> bool:
        """Is frame ``end`` back near the lower end of the movement since ``start``? (A gesture
        end in the middle of a movement is a slow patient seen through a fast tutor.)"""
        p = np.asarray(self._progress[side][start : end + 1])
        low, high = float(p.min()), float(p.max())
        return high - low < self.options.min_reach or p[-1] - low <= REST_SHARE * (high - low)

    def _repetitions(self, g: Gesture, side: int, final: bool = False) -> list[Event]:
        """The repetitions in a gesture: usually one; none for a rest; several when a fast
        patient's short rests hid a gesture end (two humps of progress in one gesture)."""
        progress = np.asarray(self._progress[side][g.start : g.end + 1])
        m = self._tutor_q.shape[0]
        peaks, props = find_peaks(
            progress, prominence=SPLIT_PROMINENCE, distance=max(1, int(0.45 * m))
        )
        # as the offline segmenter: a hump counts when it stands out by 45 % of its height
        height = progress[peaks] - float(np.percentile(progress, 5))
        peaks = peaks[props["prominences"] >= RELATIVE_PROMINENCE * height]
        cuts = [g.start + int(np.argmin(progress[a:b])) + a for a, b in itertools.pairwise(peaks)]
        bounds = [g.start, *cuts, g.end + 1]
        pieces = list(itertools.pairwise(bounds))
        found = [
            self._repetition(g, a, b - 1, side, final and k == len(pieces) - 1)
            for k, (a, b) in enumerate(pieces)
        ]
        return [e for e in found if e is not None]

    def _repetition(self, g: Gesture, a: int, b: int, side: int, final: bool) -> Event | None:
        """Model-rate frames a..b of gesture g as a repetition: None for a rest, or for a
        movement that has not come back yet (unless the stream ended)."""
        progress = np.asarray(self._progress[side][a : b + 1])
        reach = float(progress.max() - progress[0])
        back = float(progress.max() - progress[-1])
        if reach < self._floor():
            return None  # a rest between repetitions
        if not final and back < RELATIVE_PROMINENCE * reach:
            return None  # the start of a movement the next gesture holds
        start, end = self._frame_of[a], self._frame_of[b]
        tempo = (b - a + 1) / self._tutor_q.shape[0]
        kind = guidance_for(tempo, reach)
        guidance = [{"type": kind, "frames": [start, end], "text": GUIDANCE_TEXT.get(kind, "")}]
        event = {
            "event": "repetition",
            "index": len(self.repetitions),
            "start": start,
            "end": end,
            "score": round(self._score(a, b, side), 2),
            "guidance": guidance if kind else [],
            "gesture_guidance": list(g.guidance),
            "reach": round(reach, 3),
            "tempo": round(tempo, 3),
        }
        self.repetitions.append(event)
        return event

    def _floor(self) -> float:
        """Least reach of a repetition: ``min_reach``, and once a few repetitions are known, 40 %
        of their median (a twitch in a rest is not a repetition of a large movement)."""
        reaches = [r["reach"] for r in self.repetitions]
        if len(reaches) < 2:
            return self.options.min_reach
        return max(self.options.min_reach, 0.4 * float(np.median(reaches)))

    def _score(self, a: int, b: int, side: int) -> float:
        """The exercise model's repetition score of model-rate frames a..b (0-100), scored as
        the tutor's side when the patient used the other one (as offline)."""
        parts = self.model.components
        points = np.asarray(self._points[a : b + 1])
        if side:
            points = mirrored(points, parts.mirror)
        points = points[:, parts.scored_index]
        segment = relative_to_start(flatten(points))
        step = parts.scoring_step
        features = repetition_features(segment[::step], [t[::step] for t in parts.templates])
        return float(parts.scorer.score(features))


def _grounded(points: FloatArray) -> FloatArray:
    out = points.copy()
    out[:, [0, 2]] -= points[0, [0, 2]]
    return out
