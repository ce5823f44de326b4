"""A live repetition's end computes each frame's kinematics once (issue 37) and still judges as
measuring every frame of the session again does: UI-PRMD sessions (data/ui-prmd, the
repository's copy), alone and played one after another, streamed through the live aligner with
`RepetitionJudge` and with the judge it replaced (kept here), every event's every field equal
but the timings."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import numpy.typing as npt
import pytest

from analysis.bvh import Motion, Skeleton
from analysis.clinical import angle_ranges, measure
from analysis.kinematics import scaled_positions
from analysis.live import LiveAligner
from analysis.live.judged import RepetitionJudge
from analysis.online.frames import FrameKinematics
from analysis.pipeline import FittedModel
from analysis.pipeline.advice_stage import facts_of, repetition_measures
from analysis.pipeline.clinical_stage import rounded
from analysis.pipeline.gestures import Pace
from analysis.pipeline.judgement import Judgement, judge
from analysis.pipeline.prepare import mirrored
from analysis.pipeline.results import Guidance, RepetitionResult
from analysis.pipeline.stages import scoring_features
from analysis.pipeline.tutor_parts import compensations
from tests.live.test_compiled_live import session, streamed


class WholeSessionJudge(RepetitionJudge):
    """The judge before issue 37: every frame of the session measured again at each end."""

    def __init__(self, model: FittedModel, skeleton: Skeleton, mirrored: bool = False) -> None:
        super().__init__(model, skeleton, mirrored)
        self._values: list[np.ndarray] = []
        self._positions = FrameKinematics(skeleton)

    def add(self, values: np.ndarray) -> None:
        self._values.append(values)

    def score(
        self, a: int, b: int, mirror_image: bool, index: Sequence[int] | npt.NDArray[np.intp]
    ) -> float:
        frames = np.asarray(self._values[: b + 1], dtype=np.float64)
        points = scaled_positions(Motion(self.skeleton, frames, 1.0 / self.model.fps), list(index))
        parts = self.model.components
        if mirror_image:
            points = mirrored(points, parts.mirror)
        return float(parts.scorer.score(scoring_features(points, a, b, parts)))

    def judge(  # noqa: PLR0917 (as the judge's)
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
        frames = np.asarray(self._values[: b + 1], dtype=np.float64)
        motion = Motion(self.skeleton, frames, 1.0 / self.model.fps)
        series = measure(motion, body=self._body).series  # the body `find_body` finds
        bent = compensations(self._positions.positions(frames), self._body)
        rep = RepetitionResult(
            start=a, end=b, peak=a, score=score, reach=reach, tempo=tempo,
            guidance=tuple(guidance), clinical_angles=rounded(angle_ranges(series, a, b)),
        )  # fmt: skip
        measures = repetition_measures([rep], bent)[0]
        return judge(facts_of(rep, measures, number, own), self._judge)


class WholeSessionAligner(LiveAligner):
    def __init__(self, model: FittedModel, skeleton: Skeleton, fps: float) -> None:
        super().__init__(model, skeleton, fps)
        self._judge = WholeSessionJudge(model, skeleton)


def played_after(*names: str, fps: float | None = None) -> Motion:
    """Sessions of one skeleton played one after another."""
    motions = [session(name, fps) for name in names]
    return motions[0].with_frames(np.concatenate([m.frames for m in motions]))


@pytest.mark.parametrize(
    ("names", "fps"),
    [(("m07_s03_incorrect",), 120.0), (("m07_s05_incorrect",), None),
     (("m07_s02_correct", "m07_s05_incorrect", "m07_s06_correct"), None),
     (("m07_s03_incorrect", "m07_s02_correct"), 60.0)],
)  # fmt: skip
def test_repetition_end_judges_as_measuring_every_frame_again(
    live_model: FittedModel, names: tuple[str, ...], fps: float | None
) -> None:
    motion = played_after(*names, fps=fps)
    kept = streamed(LiveAligner(live_model, motion.skeleton, motion.fps), motion)
    again = streamed(WholeSessionAligner(live_model, motion.skeleton, motion.fps), motion)
    assert kept == again
    repetitions = [e for e in kept if e["event"] == "repetition"]
    assert len(repetitions) >= 5 * len(names), "the session needs repetitions to say anything"
    assert len({e["passed"] for e in repetitions}) == 2 or len(names) == 1, "both verdicts seen"


def test_spans_asked_out_of_order_are_judged_over_the_frames_up_to_their_end(
    live_model: FittedModel,
) -> None:
    """Every frame added before any is asked about, and an earlier end asked after a later one:
    each span is scored and judged over frames 0..its end, the frames kept for later ends
    left out."""
    motion = session("m07_s02_correct")
    kept = RepetitionJudge(live_model, motion.skeleton)
    again = WholeSessionJudge(live_model, motion.skeleton)
    index = LiveAligner(live_model, motion.skeleton, motion.fps)._index
    for values in motion.frames:
        kept.add(values)
        again.add(values)
    bounds = [(10, 60), (40, 120), (20, 50), (100, motion.n_frames - 1)]  # 20..50 after 40..120
    for a, b in bounds:
        for side in (False, True):
            assert kept.score(a, b, side, index) == again.score(a, b, side, index)
        args = (a, b, 1, 80.0, (), 0.9, 1.1, None)
        assert kept.judge(*args) == again.judge(*args)


def test_a_rig_whose_rest_pose_does_not_stand_is_judged_as_measuring_every_frame_again(
    live_model: FittedModel,
) -> None:
    """A rig whose rest pose says nothing of the vertical (as Bandai-Namco's and Rokoko's lie
    along +x; here UI-PRMD's body taken as one): trunk frames from the joints' lines and the
    vertical the trunk's over the frames so far, which the kept frames are read about."""
    motion = played_after("m07_s02_correct", "m07_s05_incorrect")
    kept = RepetitionJudge(live_model, motion.skeleton)
    again = WholeSessionJudge(live_model, motion.skeleton)
    kept._body = again._body = replace(kept._body, upright=False)
    for b in range(motion.n_frames):
        kept.add(motion.frames[b])
        again.add(motion.frames[b])
        if b % 60 == 59:  # a repetition's end every 60 frames
            args = (b - 59, b, b // 60 + 1, 80.0, (), 0.9, 1.1, None)
            assert kept.judge(*args) == again.judge(*args)
    positions = kept._caught_up(motion.n_frames - 1)
    assert kept._angles(positions, motion.n_frames - 1), "clinical angles read on such a rig"
    assert kept._compensations(positions, motion.n_frames - 1), "and compensations"
