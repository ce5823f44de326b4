"""The analysis pipeline end to end: the interface contract's fields on every UI-PRMD session,
typed errors
for bad input, and sensible results on synthetic performances with known truth."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import RecordingTooShortError, SkeletonMismatchError, read
from analysis.pipeline import ModelVersionError, analyse, build_model, dump_model, load_model
from analysis.pipeline.model import FORMAT_VERSION
from tests.synthetic_motion import SyntheticConfig, generate

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
FIELDS = {"frames", "fps", "landmarks", "repetitions", "score", "assessment", "feedback",
          "timings_ms"}  # fmt: skip


def landmarks(name: str) -> tuple[list[int], list[int]]:
    with open(DATA / "landmarks.csv") as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        if row["file"] == name:
            return [int(v) for v in row["frames"].split(";")], [
                int(v) for v in row["types"].split(";")
            ]
    raise LookupError(name)


@pytest.fixture(scope="module")
def models():
    out = {}
    for k in range(1, 11):
        name = f"sessions/m{k:02d}_s01_correct.bvh.gz"
        out[f"m{k:02d}"] = build_model(read(DATA / name), *landmarks(name))
    return out


def check_contract(result: dict) -> None:
    assert set(result) >= FIELDS
    assert isinstance(result["frames"], int) and result["fps"] > 0
    assert 0.0 <= result["score"] <= 100.0
    for rep in result["repetitions"]:
        assert 0 <= rep["start"] <= rep["end"] < result["frames"]
        assert 0.0 <= rep["score"] <= 100.0
    for mark in result["landmarks"]:
        assert 0 <= mark["frame"] < result["frames"] and isinstance(mark["type"], int)
    for item in result["assessment"]:
        assert all(1 <= v <= 4 for v in item["levels"].values())
    assert all(isinstance(f["text"], str) and f["text"] for f in result["feedback"])


def test_every_ui_prmd_session_gives_the_contract_fields(models):
    for path in sorted((DATA / "sessions").glob("*.bvh.gz")):
        result = analyse(read(path), models[path.name[:3]]).to_json()
        check_contract(result)
        assert len(result["repetitions"]) >= 5, path.name


def test_playback_holds_the_four_skeletons(models):
    result = analyse(read(DATA / "sessions/m07_s02_correct.bvh.gz"), models["m07"])
    arrays = result.arrays()
    n = result.to_json()["frames"]
    for key in ("patient", "patient_adjusted", "tutor", "tutor_adjusted"):
        assert arrays[f"{key}_positions"].shape == (n, 22, 3)
        assert arrays[f"{key}_positions"].dtype == np.float32
    assert not np.allclose(arrays["patient_positions"], arrays["tutor_positions"])


def test_progress_is_reported_in_order(models):
    seen = []
    analyse(read(DATA / "reps/m01_s01_e02.bvh.gz"), models["m01"],
            on_progress=lambda stage, f: seen.append(f))  # fmt: skip
    assert seen == sorted(seen) and seen[-1] == 1.0


def test_incorrect_sessions_score_lower_on_average(models):
    for ex in ("m01", "m07"):
        scores = {lab: np.mean([
            analyse(read(DATA / f"sessions/{ex}_s0{s}_{lab}.bvh.gz"), models[ex]).to_json()["score"]
            for s in (2, 3, 4)]) for lab in ("correct", "incorrect")}  # fmt: skip
        assert scores["correct"] > scores["incorrect"], (ex, scores)


def test_unmappable_skeleton_and_short_recordings_are_refused(models):
    perf = generate(SyntheticConfig(), seed=0)
    other = perf.motion.skeleton
    renamed = type(other)(
        tuple(f"bone{k}" for k in range(len(other.names))), other.parents, other.offsets,
        other.channels, other.end_site_parents, other.end_site_offsets,
    )  # fmt: skip
    with pytest.raises(SkeletonMismatchError):
        analyse(
            type(perf.motion)(renamed, perf.motion.frames, perf.motion.frame_time), models["m01"]
        )
    tiny = read(DATA / "reps/m01_s01_e02.bvh.gz")
    with pytest.raises(RecordingTooShortError):
        analyse(tiny.with_frames(tiny.frames[:3]), models["m01"])


def test_model_file_round_trip_and_version_check(models):
    buffer = io.BytesIO()
    dump_model(models["m05"], buffer)
    loaded = load_model(buffer.getvalue())
    assert loaded.key_poses.same_as(models["m05"].key_poses)
    broken = buffer.getvalue().replace(f"\n{FORMAT_VERSION}\n".encode(), b"\n99\n", 1)
    with pytest.raises(ModelVersionError):
        load_model(broken)
    with pytest.raises(ModelVersionError):
        load_model(b"something else")


def test_synthetic_repetitions_are_counted():
    tutor = generate(SyntheticConfig(n_repetitions=4), seed=0)
    model = build_model(tutor.motion, tutor.truth.landmark_frames.tolist(),
                        tutor.truth.landmark_types.tolist())  # fmt: skip
    patient = generate(SyntheticConfig(n_repetitions=6, tempo_jitter=0.2, noise_deg=0.5), seed=3)
    result = analyse(patient.motion, model).to_json()
    starts = np.array([r["start"] for r in result["repetitions"]])
    assert len(starts) == 6
    # A repetition starts at the lowest point of the rest before it (a 15-frame pause here).
    truth = patient.truth.rep_starts
    assert np.all((starts >= truth - 18) & (starts <= truth + 3)), (starts, truth)


def test_reduced_range_scores_lower_than_full_range():
    tutor = generate(SyntheticConfig(n_repetitions=4, noise_deg=0.3), seed=0)
    model = build_model(tutor.motion, tutor.truth.landmark_frames.tolist(),
                        tutor.truth.landmark_types.tolist())  # fmt: skip
    good = analyse(generate(SyntheticConfig(noise_deg=0.3), seed=5).motion, model).to_json()
    weak = analyse(
        generate(SyntheticConfig(noise_deg=0.3, range_of_motion=0.5), seed=5).motion, model
    ).to_json()
    assert good["score"] > weak["score"]
    assert any(
        r["guidance"] and r["guidance"][0]["type"] == "incomplete" for r in weak["repetitions"]
    )


def test_lost_frames_are_carried_to_the_models_frame_rate():
    from analysis.bvh import Motion
    from analysis.pipeline.clinical_stage import lost_at_rate

    motion = read(DATA / "sessions/m07_s02_correct.bvh.gz")
    lost = np.zeros(motion.n_frames, dtype=bool)
    lost[3] = True
    same = lost_at_rate({"left_shoulder": lost}, motion.frame_time, motion)["left_shoulder"]
    np.testing.assert_array_equal(same, lost)
    doubled = Motion(motion.skeleton, motion.frames, motion.frame_time / 2)
    at_double = lost_at_rate({"left_shoulder": lost}, motion.frame_time, doubled)["left_shoulder"]
    assert np.flatnonzero(at_double).tolist() == [5, 6, 7]  # 2.5, 3 and 3.5 recorded frames


def test_a_lost_shoulder_leaves_its_angles_only_where_it_was_lost(models):
    """The first repetition's frames marked lost: its left shoulder has no range there, the
    repetitions and their scores are those of the recording without marks."""
    motion = read(DATA / "sessions/m07_s02_correct.bvh.gz")
    plain = analyse(motion, models["m07"]).summary
    first = plain.repetitions[0]
    lost = np.zeros(motion.n_frames, dtype=bool)
    lost[first.start : first.end + 1] = True
    marked = analyse(motion, models["m07"], lost_frames={"left_shoulder": lost}).summary
    assert [(r.start, r.end, r.score) for r in marked.repetitions] == [
        (r.start, r.end, r.score) for r in plain.repetitions
    ]
    assert "shoulder_elevation_left" in first.clinical_angles
    assert "shoulder_elevation_left" not in marked.repetitions[0].clinical_angles
    assert marked.repetitions[1].clinical_angles == plain.repetitions[1].clinical_angles
    assert (
        marked.repetitions[0].clinical_angles["shoulder_elevation_right"]
        == (first.clinical_angles["shoulder_elevation_right"])
    )
