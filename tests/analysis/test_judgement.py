"""One judgement per repetition (issue 34): verdict, guidance and reasons made once, from one set
of measurements, offline and live alike. The rules are checked on the result JSON by
`bench.eval_judgement.broken_rules` (the whole evaluation: ``python -m bench.eval_judgement``)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from analysis.assessment.findings import Reference, RepetitionMeasures
from analysis.bvh import read
from analysis.feedback import Grammar
from analysis.feedback.text import correction_rules
from analysis.live import repetition_words
from analysis.pipeline import AnalysisSummary, analyse, build_model
from analysis.pipeline.judgement import Judge, RepetitionFacts, judge, one_per_axis
from bench.eval_judgement import broken_rules, offline_words, streamed
from tests.analysis.guidance_cases import range_scaled

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct.bvh.gz"  # shoulder abduction of the right arm
ARM = "shoulder_elevation_right"
JUDGE = Judge(
    Reference({ARM: 142.0}, {ARM: 4.0}, involved={ARM}), False, 70.0,
    (Grammar(tuple(correction_rules())),), "right arm",
)  # fmt: skip


def facts(score: float, rose: float, guidance: tuple[str, ...] = (), tempo: float = 1.0,
          reach: float = 1.0) -> RepetitionFacts:  # fmt: skip
    return RepetitionFacts(3, score, guidance, RepetitionMeasures(0, {ARM: rose}, tempo,
                                                                   reach=reach))  # fmt: skip


def test_one_type_per_axis():
    assert one_per_axis(["overdone", "too fast", "incomplete", "too slow"]) == (
        "overdone", "too fast",
    )  # fmt: skip
    verdict = judge(facts(40.0, 140.0, ("incomplete", "overdone")), JUDGE)
    assert verdict.guidance == ("incomplete",)


def test_guidance_never_points_against_the_correction_of_its_repetition():
    """Issue 34: "Not so far" beside "raise your right arm higher, by about 52°"."""
    verdict = judge(facts(40.0, 89.0, ("overdone",)), JUDGE)
    assert not verdict.passed
    assert "overdone" not in verdict.guidance
    assert verdict.reasons[0].startswith("Raise your right arm higher, by about 53°")
    assert [h.kind for h in verdict.hits] == ["less"]


def test_a_failed_repetition_always_has_a_reason_it_can_act_on():
    # within every tolerance, failed by its score alone: told its largest difference
    verdict = judge(facts(55.0, 135.0), JUDGE)
    assert not verdict.passed and verdict.reasons
    assert verdict.reasons[0].startswith("Raise your right arm higher, by about 7°")
    words = repetition_words({"index": 2, "passed": False, "reasons": list(verdict.reasons)})
    assert "score" not in words and "tutor" not in words
    # a guided one: its guidance first, never a difference pointing against it
    slow = judge(facts(55.0, 150.0, ("incomplete",)), JUDGE)
    assert slow.reasons[0] == "Go further: reach the demonstration's end position."
    assert all("Lower" not in r for r in slow.reasons)


def test_a_plain_error_fails_whatever_the_score_and_a_pass_is_praised():
    plain = judge(facts(90.0, 60.0, reach=0.5), JUDGE)
    assert not plain.passed and "Raise your right arm higher" in plain.reasons[0]
    clean = judge(facts(90.0, 140.0), JUDGE)
    assert clean.passed and clean.reasons == ()
    assert repetition_words({"index": 0, "passed": True, "reasons": []}) == (
        "Repetition 1: well done."
    )


def _landmarks(name: str) -> tuple[list[int], list[int]]:
    with open(DATA / "landmarks.csv") as handle:
        row = next(r for r in csv.DictReader(handle) if r["file"] == name)
    return [int(v) for v in row["frames"].split(";")], [int(v) for v in row["types"].split(";")]


@pytest.fixture(scope="module")
def model():
    return build_model(read(DATA / TUTOR), *_landmarks(TUTOR))


def test_results_keep_the_rules_and_store_the_reasons(model):
    """A cold-start incorrect take and a correct one whose reach is cut to 55 % (issue 34)."""
    incorrect = read(DATA / "sessions/m07_s03_incorrect.bvh.gz")
    cut = range_scaled(read(DATA / "sessions/m07_s02_correct.bvh.gz"), 0.55)
    for motion in (incorrect, cut):
        result = analyse(motion, model).to_json()
        assert broken_rules(result) == []
        failed = [r for r in result["repetitions"] if r["passed"] is False]
        assert failed and result["advice"]["corrections"]
        assert all(r["reasons"] for r in failed)
        summary = AnalysisSummary.from_json(result)
        assert [r.reasons for r in summary.repetitions] == [
            tuple(r["reasons"]) for r in result["repetitions"]
        ]
    # a run stored before reasons reads without them
    older = {k: v for k, v in result["repetitions"][0].items() if k != "reasons"}
    assert AnalysisSummary.from_json({"repetitions": [older]}).repetitions[0].reasons == ()


def test_live_words_are_the_offline_judgement_of_the_same_frames(model):
    motion = read(DATA / "sessions/m07_s02_incorrect.bvh.gz")
    live = streamed(motion, model)
    assert len(live) >= 8 and any(not e["passed"] for e in live)
    assert [e["words"] for e in live] == offline_words(motion, model, live)
    for event in live:
        assert event["passed"] or event["reasons"]
        assert "tutor" not in event["words"].lower()
