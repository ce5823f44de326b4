"""The small, fixed version of `bench/eval_recorders.py`: UI-PRMD's sit to stand (m05) of subject
s01, recorded at once by its Kinect (BVH) and by Vicon (Plug-in Gait ``.trc``, z up, 100 fps),
against the exercise made from s03's Kinect session: the same repetition count, the same
pass/fail and scores within 5 points from both recorders.
The full table (every paired take, both kinds of reference) is in docs/EVALUATION.md."""

from __future__ import annotations

import pytest

from analysis.bvh import read
from bench.eval_recorders import DATA, SCORE_POINTS, judged, kinect_model, vicon_motion

TAKES = ("m05_s01_correct",)


@pytest.mark.parametrize("take", TAKES)
def test_both_recorders_give_one_answer(take):
    model = kinect_model("m05")
    kinect = judged(read(DATA / "sessions" / f"{take}.bvh.gz"), model)
    vicon = judged(vicon_motion(f"{take}.trc.gz"), model)
    assert kinect[0] == vicon[0] == 10
    assert kinect[2] == vicon[2]
    assert abs(kinect[1] - vicon[1]) <= SCORE_POINTS, (kinect, vicon)
