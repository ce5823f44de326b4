"""A live repetition judged as the offline analysis judges one (issue 34): the same measurements
of its frames — score, paper 001's pace, clinical angles and compensations — handed to the one
judgement (`analysis.pipeline.judgement.judge`, through `advice_stage.facts_of`), so the words a
patient hears live are the reasons the recording's page gives for the same frames."""

from __future__ import annotations

import weakref
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from analysis.assessment.compensations import checked, raw_series
from analysis.bvh import Motion, Skeleton
from analysis.clinical import angle_ranges
from analysis.clinical.angles import frame_angles, take_angles
from analysis.clinical.body import Geometry, find_body, geometry, take_vertical
from analysis.clinical.measured import within_limits
from analysis.kinematics import kinematics
from analysis.kinematics.forward_kinematics import heading_facing
from analysis.kinematics.posefeatures import body_scale
from analysis.pipeline.advice_stage import facts_of, judge_of, repetition_measures
from analysis.pipeline.clinical_stage import rounded
from analysis.pipeline.gestures import Pace
from analysis.pipeline.judgement import GUIDANCE_TEXT, Judge, Judgement, judge
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import mirrored
from analysis.pipeline.results import Guidance, RepetitionResult
from analysis.pipeline.stages import scoring_features

FloatArray = npt.NDArray[np.float64]


class _Rows:
    """Arrays growing by rows (frames), with room doubled as needed: the frames so far are a
    view, never a copy of the whole session."""

    def __init__(self) -> None:
        self.n = 0
        self._arrays: dict[str, FloatArray] = {}

    def extend(self, **rows: FloatArray) -> None:
        """Append the same number of rows to each named array (none: nothing to keep)."""
        if not rows:
            return
        k = len(next(iter(rows.values())))
        for name, part in rows.items():
            held = self._arrays.get(name)
            if held is None or held.shape[0] < self.n + k:
                grown = np.empty((max(2 * self.n + k, 64), *part.shape[1:]), dtype=np.float64)
                if held is not None:
                    grown[: self.n] = held[: self.n]
                self._arrays[name] = held = grown
            held[self.n : self.n + k] = part
        self.n += k

    def __getitem__(self, name: str) -> FloatArray:
        return self._arrays[name][: self.n]

    def __contains__(self, name: str) -> bool:
        return name in self._arrays

    @property
    def names(self) -> list[str]:
        """The arrays' names, in the order first extended."""
        return list(self._arrays)


_JUDGES: weakref.WeakKeyDictionary[FittedModel, dict[bool, Judge]] = weakref.WeakKeyDictionary()


def _judge_of(model: FittedModel, mirrored: bool) -> Judge:
    """`judge_of`, made once per model and side (it reads only the model, and is frozen)."""
    sides = _JUDGES.setdefault(model, {})
    if mirrored not in sides:
        sides[mirrored] = judge_of(model, mirrored)
    return sides[mirrored]


class RepetitionJudge:
    """Judges the repetitions of one stream: frames are the stream's BVH channel values at the
    model's rate (`add`), a repetition is model-rate frames a..b (`judge`).

    The offline analysis measures a whole recording, and some of its measures are statistics of
    every frame (the mean heading and median body size the score is taken over, the share of
    frames beyond the body's limits that leaves a clinical angle out, the ankle's zero from the
    standing frames, the take's vertical). Each frame's forward kinematics, trunk frames, limb
    axes, clinical angles (`frame_angles`) and compensations as read are computed once, at the
    first repetition's end after it (`_caught_up`), and only the whole-recording steps run over
    the frames so far (`take_angles`: the ankle's zero, a shoulder angle's share of defined
    frames, the trunk against the take's vertical; the limits; the compensations' checks): the
    same numbers, to the last bit, as measuring every frame again
    (`tests/live/test_repetition_end`), since each of those per-frame steps gives a frame the
    same values whatever frames are computed with it."""

    def __init__(self, model: FittedModel, skeleton: Skeleton, mirrored: bool = False) -> None:
        self.model, self.skeleton = model, skeleton
        self._judge = _judge_of(model, mirrored)
        self._body = find_body(skeleton)
        self._frames = _Rows()  # channel values
        self._kin = _Rows()  # world positions and the heading, of the frames done
        self._geo = _Rows()  # `Geometry`'s trunk frames and limb axes, of the frames done
        self._each = _Rows()  # `frame_angles` of the frames done
        self._bent = _Rows()  # the compensations as read (`raw_series`), of the frames done
        self._bent_up: FloatArray | None = None  # the vertical they were read about
        self._frame_time = 1.0 / model.fps
        self._rest_axes: dict[str, FloatArray] = {}  # `geometry`'s limb axes in the rest pose

    def add(self, values: FloatArray) -> None:
        """One model-rate frame's channel values."""
        self._frames.extend(values=np.asarray(values, dtype=np.float64)[None])

    def set_side(self, mirrored: bool) -> None:
        """The patient uses the other side (mirror image) from now on."""
        if mirrored != self._judge.mirrored:
            self._judge = _judge_of(self.model, mirrored)

    def _motion(self, b: int) -> Motion:
        """Frames 0..b."""
        return Motion(self.skeleton, self._frames["values"][: b + 1], self._frame_time)

    def _caught_up(self, b: int) -> FloatArray:
        """The world positions (b + 1, J, 3) of frames 0..b, computing the kinematics of only
        the frames not yet done (and their trunk frames and limb axes, which read no other
        frame); the rotations are not kept, for a long session's memory."""
        done = self._kin.n
        if done <= b:
            motion = self._motion(b).with_frames(self._frames["values"][done : b + 1])
            new = kinematics(motion)
            self._kin.extend(positions=new.positions, heading=new.heading)
            geo = geometry(motion, kin=new, body=self._body)
            trunk = {"pelvis": geo.pelvis, "thorax": geo.thorax}
            self._geo.extend(
                **{k: v for k, v in trunk.items() if v is not None},
                **{f"axis {k}": v for k, v in geo.axes.items()},
            )
            self._rest_axes = geo.rest_axes
            self._each.extend(**frame_angles(geo))
        return self._kin["positions"][: b + 1]

    def _vertical(self, positions: FloatArray) -> FloatArray:
        """The take's vertical, as `geometry` and `tutor_parts.compensations` find it: the
        rig's, or for a rig whose rest pose does not stand, the trunk's over frames so far."""
        return self._body.up if self._body.upright else take_vertical(positions, self._body)

    def _angles(self, positions: FloatArray, b: int) -> dict[str, FloatArray]:
        """`measure(...).series` of frames 0..b: the clinical angles of the geometry done, with
        the take's vertical and the whole-take steps (the ankle's zero, the share of frames
        defined, beyond the body's limits or noisy) over every frame so far."""
        parts = {k: self._geo[k][: b + 1] for k in ("pelvis", "thorax") if k in self._geo}
        axes = {k[5:]: self._geo[k][: b + 1] for k in self._geo.names if k.startswith("axis ")}
        geo = Geometry(
            parts.get("pelvis"), parts.get("thorax"), axes, self._rest_axes,
            self._vertical(positions), self._body.upright,
        )  # fmt: skip
        each = {name: self._each[name][: b + 1] for name in self._each.names}
        return within_limits(take_angles(geo, each)).series

    def _compensations(self, positions: FloatArray, b: int) -> dict[str, FloatArray]:
        """`tutor_parts.compensations` of frames 0..b: each frame read once about the take's
        vertical (again from the first frame should that vertical change), each measure then
        checked over every frame so far (`compensation_measures`)."""
        up = self._vertical(positions)
        if self._bent_up is None or not np.array_equal(up, self._bent_up):
            self._bent, self._bent_up = _Rows(), up
        done = self._bent.n
        if done <= b and (read := raw_series(positions[done : b + 1], self._body.joints, up)):
            self._bent.extend(**read)
        series = {}
        for name in self._bent.names:
            kept, _ = checked(name, self._bent[name][: b + 1])
            if kept is not None:
                series[name] = kept
        return series

    def score(
        self, a: int, b: int, mirror_image: bool, index: Sequence[int] | npt.NDArray[np.intp]
    ) -> float:
        """The exercise model's score of frames a..b (0-100), as the offline analysis scores
        it (`stages.scoring_features`) from the frames so far: their positions facing their mean
        heading over their median body size; scored as the tutor's side for the mirror image;
        ``index``: the stream's joint of each of the model's."""
        positions = self._caught_up(b)
        # `scaled_positions` of frames 0..b, gathered for the repetition's frames alone
        points = heading_facing(positions, self._kin["heading"][: b + 1])
        scale = body_scale(points, self.skeleton.parents)
        points = np.take(points[a : b + 1], list(index), axis=1) / scale
        parts = self.model.components
        if mirror_image:
            points = mirrored(points, parts.mirror)
        return float(parts.scorer.score(scoring_features(points, 0, b - a, parts)))

    def judge(  # noqa: PLR0917 (a repetition's live measurements)
        self,
        a: int,
        b: int,
        number: int,
        score: float,
        guidance: Sequence[Guidance],
        reach: float,
        tempo: float,
        own: Pace | None,
    ) -> Judgement:
        """The judgement of frames a..b (repetition ``number``, 1-based): its ``score``, the pace
        rule's ``guidance``, its ``reach`` along the movement and ``tempo`` (over the tutor's
        repetition); ``own``: the patient's usual pace from an earlier session."""
        # measured over every frame so far, as the offline analysis measures a whole recording
        # (a measure it leaves out as beyond the body or too noisy is judged on the take)
        positions = self._caught_up(b)
        series = self._angles(positions, b)
        bent = self._compensations(positions, b)
        rep = RepetitionResult(
            start=a, end=b, peak=a, score=score, reach=reach, tempo=tempo,
            guidance=tuple(guidance), clinical_angles=rounded(angle_ranges(series, a, b)),
        )  # fmt: skip
        measures = repetition_measures([rep], bent)[0]
        return judge(facts_of(rep, measures, number, own), self._judge)


def guidance_events(
    found: Sequence[Guidance], verdict: Judgement, stream_frames: Sequence[int]
) -> list[dict[str, object]]:
    """The guidance a repetition event carries: the pace rule's types the judgement kept, each
    with the stream frames it concerns (``stream_frames``: the stream frame of each of the
    repetition's model-rate frames) and its words."""
    last = len(stream_frames) - 1
    return [
        {"type": g.type, "frames": [stream_frames[min(last, f)] for f in g.frames],
         "text": GUIDANCE_TEXT[g.type]}
        for g in found if g.type in verdict.guidance
    ]  # fmt: skip
