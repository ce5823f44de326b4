"""The pipeline runs the papers' stages in order (issue: key poses, periodic analysis,
synchronisation, gesture-based alignment), on a UI-PRMD session and on a synthetic skeleton built
like Bandai-Namco's files (a static root above the hips, six channels on every joint)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import Motion, Skeleton, read
from analysis.pipeline import analyse, build_model
from analysis.pipeline.run import STAGES
from tests.synthetic_motion import SyntheticConfig, generate

DATA = Path(__file__).resolve().parents[2] / "data" / "ui-prmd"
PAPER_STAGES = (
    "landmark_identification",
    "landmark_refining",
    "periodic_analysis",
    "repetitions",
    "synchronisation",
    "alignment",
    "assessment",
    "scores",
    "performance_level",
    "adjustment",
    "clinical_angles",
    "feedback",  # after the angles: the corrections compare them with the tutor's
)


def _landmarks(name: str) -> tuple[list[int], list[int]]:
    with open(DATA / "landmarks.csv") as handle:
        row = next(r for r in csv.DictReader(handle) if r["file"] == name)
    return [int(v) for v in row["frames"].split(";")], [int(v) for v in row["types"].split(";")]


def bandai_like(motion: Motion) -> Motion:
    """The motion under a static extra root, every joint with position + rotation channels (the
    position values being the joint's offset, as those files store them)."""
    sk = motion.skeleton
    six = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    skeleton = Skeleton(
        names=("joint_Root", *sk.names),
        parents=np.concatenate([[-1], sk.parents + 1]).astype(np.int64),
        offsets=np.vstack([np.zeros(3), sk.offsets]),
        channels=(six,) * (len(sk.names) + 1),
        end_site_parents=sk.end_site_parents + 1,
        end_site_offsets=sk.end_site_offsets,
    )
    columns = [np.zeros((motion.n_frames, 6))]
    for joint, (start, channels) in enumerate(zip(sk.channel_starts, sk.channels, strict=True)):
        values = dict(zip(channels, motion.frames[:, start : start + len(channels)].T, strict=True))
        block = np.empty((motion.n_frames, 6))
        for k, channel in enumerate(six):
            block[:, k] = values.get(channel, sk.offsets[joint, "XYZ".index(channel[0])])
        columns.append(block)
    return Motion(skeleton, np.hstack(columns), motion.frame_time)


def assert_papers_pipeline(summary) -> None:
    # the papers' stages in their order; "match" (does the recording show the exercise at all,
    # issue 25) is ours and sits between counting repetitions and synchronisation
    papers_order = [key for key, _ in STAGES if key != "match"]
    assert papers_order[1 : len(PAPER_STAGES) + 1] == list(PAPER_STAGES)
    assert summary.match.fits and "match" in summary.timings_ms
    assert set(PAPER_STAGES) <= set(summary.timings_ms)
    assert summary.segmentation == "landmarks"
    starts = {m.frame for m in summary.landmarks if m.type == 1}
    assert summary.repetitions
    for rep in summary.repetitions:
        assert rep.start in starts  # a type-1 key pose starts every repetition
        inside = [m.type for m in summary.landmarks if rep.start < m.frame <= rep.end]
        assert 2 in inside  # and the cycle's end of range lies inside it
        assert rep.alignment_tau is not None and -1.0 <= rep.alignment_tau <= 1.0
        assert rep.similarity is not None and rep.similarity >= 0.0
        assert rep.gbdtw_score is not None and 0.0 <= rep.gbdtw_score <= 100.0
        assert rep.passed == (rep.score >= summary.pass_threshold)


@pytest.mark.slow
def test_ui_prmd_session_goes_through_every_paper_stage():
    tutor_name = "sessions/m01_s01_correct.bvh.gz"
    model = build_model(read(DATA / tutor_name), *_landmarks(tutor_name))
    summary = analyse(read(DATA / "sessions/m01_s03_correct.bvh.gz"), model).summary
    assert_papers_pipeline(summary)
    assert summary.repetition_count == 10
    assert summary.periodic.candidates > 0


@pytest.mark.slow
def test_bandai_like_skeleton_goes_through_every_paper_stage():
    tutor = generate(SyntheticConfig(n_repetitions=5, noise_deg=0.3), seed=0)
    model = build_model(
        bandai_like(tutor.motion),
        tutor.truth.landmark_frames.tolist(),
        tutor.truth.landmark_types.tolist(),
    )
    patient = generate(SyntheticConfig(n_repetitions=6, tempo_jitter=0.2, noise_deg=0.5), seed=4)
    summary = analyse(bandai_like(patient.motion), model).summary
    assert_papers_pipeline(summary)
    assert summary.repetition_count == 6
    # each repetition is cut in the rest before its movement starts (after the previous one ends)
    found = np.array([r.start for r in summary.repetitions])
    assert np.all(found <= patient.truth.rep_starts)
    assert np.all(found[1:] >= patient.truth.rep_ends[:-1])
