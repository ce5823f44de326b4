"""What a live session tells the patient after each repetition: "well done" only for a passed
one; a failed one always hears a reason it can act on (its judgement's first reason: a score is
not a reason), in words for patients ("the demonstration", never "the tutor")."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from analysis.bvh import read
from analysis.live import LiveSession, header_text, repetition_words
from analysis.pipeline import build_model

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
TUTOR = "sessions/m07_s01_correct.bvh.gz"
FAILING = "sessions/m07_s02_incorrect.bvh.gz"  # an incorrect take: most repetitions fail


def _landmarks(name: str) -> tuple[list[int], list[int]]:
    with open(DATA / "landmarks.csv") as handle:
        row = next(r for r in csv.DictReader(handle) if r["file"] == name)
    return [int(v) for v in row["frames"].split(";")], [int(v) for v in row["types"].split(";")]


@pytest.fixture(scope="module")
def streamed() -> list[dict]:
    """The incorrect take streamed through a live session in batches, as a capture client."""
    model = build_model(read(DATA / TUTOR), *_landmarks(TUTOR))
    motion = read(DATA / FAILING)
    session = LiveSession(model, max_fps=1e9, burst=1e9)  # no frame dropped, however fast
    events = session.handle({"type": "start", "header": header_text(motion)})
    for seq in range(0, motion.n_frames, 32):
        batch = motion.frames[seq : seq + 32].tolist()
        events += session.handle({"type": "frames", "seq": seq, "frames": batch})
    events += session.handle({"type": "end"})
    threshold = model.components.papers.threshold.value
    return [{**e, "threshold": threshold} for e in events if e["event"] == "repetition"]


def test_failed_repetitions_are_never_praised_and_always_told_why(streamed):
    failed = [r for r in streamed if not r["passed"]]
    assert len(failed) >= 3, "the take needs failed repetitions for the test to say anything"
    for rep in failed:
        words = rep["words"]
        assert "well done" not in words.lower()
        assert rep["reasons"], rep
        assert words == f"Repetition {rep['index'] + 1}: {rep['reasons'][0]}"
        assert "score" not in words and "passes" not in words, words


def test_passed_repetitions_without_a_tip_are_praised(streamed):
    passed = [r for r in streamed if r["passed"]]
    assert passed, "the take needs a passed repetition too"
    for rep in passed:
        if not rep["reasons"]:
            assert rep["words"] == f"Repetition {rep['index'] + 1}: well done."
        else:
            assert rep["reasons"][0] in rep["words"]
    # a score under the pass mark never passes (a plain error may fail a higher one)
    assert all(r["score"] >= r["threshold"] for r in passed)


def test_patients_hear_of_the_demonstration_never_of_the_tutor(streamed):
    for rep in streamed:
        said = " ".join([rep["words"], *rep["reasons"], *(g["text"] for g in rep["guidance"])])
        assert "tutor" not in said.lower(), said


def test_the_words_for_each_case():
    tip = {"type": "incomplete", "frames": [3, 9], "text": "Go further."}
    rep = {"index": 4, "score": 31.4, "passed": False, "guidance": [], "reasons": ["Bend more."]}
    assert repetition_words(rep, 70.0) == "Repetition 5: Bend more."
    told = repetition_words({**rep, "reasons": [], "guidance": [tip]})
    assert told == "Repetition 5: Go further."
    assert repetition_words({**rep, "reasons": [], "passed": True}) == "Repetition 5: well done."
    assert "score" not in repetition_words({**rep, "reasons": []})
