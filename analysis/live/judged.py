"""A live repetition judged as the offline analysis judges one (issue 34): the same measurements
of its frames — score, paper 001's pace, clinical angles and compensations — handed to the one
judgement (`analysis.pipeline.judgement.judge`, through `advice_stage.facts_of`), so the words a
patient hears live are the reasons the recording's page gives for the same frames."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from analysis.bvh import Motion, Skeleton
from analysis.clinical import angle_ranges, measure
from analysis.clinical.body import find_body
from analysis.kinematics import scaled_positions
from analysis.online.frames import FrameKinematics
from analysis.pipeline.advice_stage import facts_of, judge_of, repetition_measures
from analysis.pipeline.clinical_stage import rounded
from analysis.pipeline.gestures import Pace
from analysis.pipeline.judgement import GUIDANCE_TEXT, Judgement, judge
from analysis.pipeline.model import FittedModel
from analysis.pipeline.prepare import mirrored
from analysis.pipeline.results import Guidance, RepetitionResult
from analysis.pipeline.stages import scoring_features
from analysis.pipeline.tutor_parts import compensations

FloatArray = npt.NDArray[np.float64]


class RepetitionJudge:
    """Judges the repetitions of one stream: frames are the stream's BVH channel values at the
    model's rate (`add`), a repetition is model-rate frames a..b (`judge`)."""

    def __init__(self, model: FittedModel, skeleton: Skeleton, mirrored: bool = False) -> None:
        self.model, self.skeleton = model, skeleton
        self._judge = judge_of(model, mirrored)
        self._kinematics = FrameKinematics(skeleton)
        self._body = find_body(skeleton)
        self._values: list[FloatArray] = []

    def add(self, values: FloatArray) -> None:
        """One model-rate frame's channel values."""
        self._values.append(values)

    def set_side(self, mirrored: bool) -> None:
        """The patient uses the other side (mirror image) from now on."""
        if mirrored != self._judge.mirrored:
            self._judge = judge_of(self.model, mirrored)

    def score(
        self, a: int, b: int, mirror_image: bool, index: Sequence[int] | npt.NDArray[np.intp]
    ) -> float:
        """The exercise model's score of frames a..b (0-100), as the offline analysis scores
        it (`stages.scoring_features`) from the frames so far: their positions facing their mean
        heading over their median body size; scored as the tutor's side for the mirror image;
        ``index``: the stream's joint of each of the model's."""
        frames = np.asarray(self._values[: b + 1], dtype=np.float64)
        motion = Motion(self.skeleton, frames, 1.0 / self.model.fps)
        points = scaled_positions(motion, list(index))
        parts = self.model.components
        if mirror_image:
            points = mirrored(points, parts.mirror)
        return float(parts.scorer.score(scoring_features(points, a, b, parts)))

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
        frames = np.asarray(self._values[: b + 1], dtype=np.float64)
        motion = Motion(self.skeleton, frames, 1.0 / self.model.fps)
        series = measure(motion).series
        bent = compensations(self._kinematics.positions(frames), self._body)
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
