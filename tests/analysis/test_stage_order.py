"""The pipeline runs its stages in the order of its one list (`analysis.pipeline.stage_order`):
progress words and fractions, ``timings_ms`` and the stages a recording that does not show the
exercise still gets all come from that list, and a stage out of it is refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from analysis.bvh import read
from analysis.pipeline import analyse, build_model
from analysis.pipeline.run import STAGES, StageTimer
from analysis.pipeline.stage_order import ORDER, Stage, StageOrder, StageOrderError

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
TUTOR = "sessions/m01_s01_correct.bvh.gz"


def tutor_marks() -> tuple[list[int], list[int]]:
    for line in (DATA / "landmarks.csv").read_text().splitlines():
        if line.startswith(TUTOR):
            _, frames, types = line.split(",")
            return [int(v) for v in frames.split(";")], [int(v) for v in types.split(";")]
    raise LookupError(TUTOR)


@pytest.fixture(scope="module")
def model():
    return build_model(read(DATA / TUTOR), *tutor_marks())


def analysed(model, session: str):
    reported: list[tuple[str, float]] = []
    result = analyse(
        read(DATA / f"sessions/{session}.bvh.gz"),
        model,
        on_progress=lambda label, fraction: reported.append((label, fraction)),
    )
    return result.summary, reported


def expected_progress(stages: list[Stage]) -> list[tuple[str, float]]:
    return [(s.label, ORDER.index(s) / len(ORDER)) for s in stages] + [("done", 1.0)]


def test_a_fitting_recording_goes_through_every_stage_of_the_list(model):
    summary, reported = analysed(model, "m01_s03_correct")
    assert summary.match.fits
    assert list(summary.timings_ms) == [stage.key for stage in ORDER]
    assert reported == expected_progress(list(ORDER))


def test_a_recording_of_another_exercise_gets_the_stages_marked_for_it(model):
    summary, reported = analysed(model, "m07_s03_correct")
    assert not summary.match.fits
    upto_match = [s for s in ORDER[: [s.key for s in ORDER].index("match") + 1]]
    ran = upto_match + [s for s in ORDER if s.if_unfit]
    assert list(summary.timings_ms) == [stage.key for stage in ran]
    assert reported == expected_progress(ran)


def test_the_run_modules_pairs_are_read_from_the_list():
    assert tuple((stage.key, stage.label) for stage in ORDER) == STAGES
    assert len({stage.key for stage in ORDER}) == len(ORDER)


def test_a_stage_out_of_the_lists_order_is_refused():
    order = StageOrder()
    order.enter("prepare")
    order.enter("match")
    with pytest.raises(StageOrderError, match="repetitions"):
        order.enter("repetitions")
    with pytest.raises(StageOrderError, match="unknown"):
        StageOrder().enter("unknown")
    with pytest.raises(StageOrderError):  # the same stage twice
        order.enter("match")


def test_the_timer_refuses_before_reporting_or_timing():
    reported: list[tuple[str, float]] = []
    timer = StageTimer(lambda label, fraction: reported.append((label, fraction)))
    with timer("landmark_refining"):
        pass
    with pytest.raises(StageOrderError), timer("prepare"):
        pass
    assert reported == [("placing key poses precisely", 2 / len(ORDER))]
    assert list(timer.timings) == ["landmark_refining"]
    # a programming error, not bad input: the command line must not turn it into exit 2
    assert not issubclass(StageOrderError, ValueError)
