"""Files that common readers open although they bend the BVH format: each loads, and
`Motion.warnings` says what was bent. Malformed neighbours of each quirk still raise `BVHError`."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from analysis.bvh import BVHError, read
from analysis.kinematics import positions
from tests.analysis import bvh_cases as bc
from tests.analysis.test_bvh import SMALL_FRAMES, assert_small

S = bc.SMALL
ROW = "1 2 3 4 5 6 7 8 9"


def test_a_clean_file_has_no_warnings():
    assert read(S).warnings == ()


def test_frame_lines_beyond_the_declared_count_are_kept_with_a_warning():
    motion = read(S + ROW + "\n" + ROW + "\n")
    assert motion.n_frames == 5
    np.testing.assert_array_equal(motion.frames[:3], SMALL_FRAMES)
    np.testing.assert_array_equal(motion.frames[3:], [[1, 2, 3, 4, 5, 6, 7, 8, 9]] * 2)
    (warning,) = motion.warnings
    assert "3 frames declared but 5 frame lines found" in warning
    assert warning.startswith("line 17: ")


def test_a_malformed_extra_frame_line_is_still_an_error():
    with pytest.raises(BVHError, match="frame line has 3 values") as caught:
        read(S + "1 2 3\n")
    assert caught.value.line == bc.SMALL_FIRST_FRAME_LINE + 3


def test_extra_frame_lines_respect_the_callers_value_cap():
    with pytest.raises(BVHError, match="more frame lines than the 3 declared"):
        read(S + ROW + "\n", max_values=27)


def test_a_stray_word_after_end_site_is_ignored_with_a_warning():
    motion = read(S.replace("End Site", "End Site Knee_End"))
    assert_small(motion)
    assert motion.warnings == ("line 10: ignored 'Knee_End' after 'End Site'",)


def test_end_without_site_is_still_an_error():
    with pytest.raises(BVHError, match="expected 'End Site' but found 'End Knee_End'"):
        read(S.replace("End Site", "End Knee_End"))


def test_a_file_whose_skeleton_starts_with_joint_reads_it_as_the_root():
    motion = read(S.replace("ROOT Hips", "JOINT Hips"))
    assert_small(motion)
    assert motion.warnings == ("line 2: the skeleton starts with JOINT instead of ROOT",)


def test_an_extra_keyword_line_inside_a_joint_is_skipped_with_a_warning():
    motion = read(bc.insert_line(S, 9, "\t\tJOINTTYPE ball 3"))
    assert_small(motion)
    assert motion.warnings == (
        "line 9: ignored the unknown line 'JOINTTYPE ball 3' in joint 'Knee'",
    )


def test_a_stray_number_inside_a_joint_is_still_an_error():
    with pytest.raises(BVHError, match="unexpected '5' in joint 'Knee'") as caught:
        read(bc.insert_line(S, 9, "\t\t5"))
    assert caught.value.line == 9


SIX = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Knee
\t{
\t\tOFFSET 0 -40 0
\t\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\t\tJOINT Ankle
\t\t{
\t\t\tOFFSET 0 -38 2
\t\t\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0 0 10
\t\t\t}
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.04
"""


def test_position_channels_near_zero_are_added_to_the_offset():
    # MakeHuman-style: non-root translations are small deltas from the OFFSET.
    rows = "1 90 2 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n1 90 2 0 0 0 0.5 0 0 0 0 0 0 0 0.2 0 0 0\n"
    motion = read(SIX + rows)
    np.testing.assert_allclose(motion.frames[:, 6:9], np.array([[0, -40, 0], [0.5, -40, 0]]))
    np.testing.assert_allclose(motion.frames[:, 12:15], np.array([[0, -38, 2], [0, -38, 2.2]]))
    np.testing.assert_allclose(positions(motion)[0, 2], [1, 12, 4])
    (warning,) = motion.warnings
    assert "position channels on 2 joints other than the root" in warning
    assert "added to each joint's OFFSET" in warning


def test_position_channels_near_the_offset_replace_it():
    # Bandai-Namco / MotionBuilder style: the values are the translation itself.
    rows = "1 90 2 0 0 0 0 -40 0 0 0 0 0 -38 2 0 0 0\n1 90 2 0 0 0 0 -41 0 0 0 0 0 -38 2 0 0 0\n"
    motion = read(SIX + rows)
    np.testing.assert_array_equal(motion.frames[1, 6:9], [0, -41, 0])
    np.testing.assert_allclose(positions(motion)[1, 2], [1, 11, 4])
    (warning,) = motion.warnings
    assert "replacing its OFFSET" in warning


def test_warnings_survive_slicing():
    motion = read(S.replace("ROOT Hips", "JOINT Hips"))
    assert motion.with_frames(motion.frames[:1]).warnings == motion.warnings


# Issue 25: two third-party files ---------------------------------------------------------------

QUIRKS = Path(__file__).parent / "fixtures" / "quirks"
RIGS = Path(__file__).resolve().parents[2] / "data" / "rigs"


def reference_positions(motion) -> np.ndarray:
    """World positions as readers that compose 4×4 transforms compute them (fairmotion, the
    Meredith–Maddock description): global = parent · T(OFFSET) · T(position channels) · R, with R
    the rotation channels composed intrinsically in declared order (scipy's upper-case axes).
    Independent of `analysis.kinematics`; ``motion.frames`` hold the replacing convention, so the
    position channels here are the values minus the OFFSET."""
    sk = motion.skeleton
    out = np.empty((motion.n_frames, len(sk.names), 3))
    for f, row in enumerate(motion.frames):
        glob: list[np.ndarray] = []
        for j, channels in enumerate(sk.channels):
            start = int(sk.channel_starts[j])
            local = np.eye(4)
            local[:3, 3] = sk.offsets[j]
            rotation_axes = "".join(c[0] for c in channels if c.endswith("rotation"))
            angles = [row[start + k] for k, c in enumerate(channels) if c.endswith("rotation")]
            for k, c in enumerate(channels):
                if c.endswith("position"):
                    local["XYZ".index(c[0]), 3] += row[start + k]
            if rotation_axes:
                local[:3, :3] = Rotation.from_euler(rotation_axes, angles, degrees=True).as_matrix()
            parent = sk.parents[j]
            glob.append(local if parent < 0 else glob[parent] @ local)
            out[f, j] = glob[j][:3, 3]
    return out


def test_end_site_with_digits_glued_reads_as_end_site_with_a_warning():
    motion = read(QUIRKS / "end_site_numbered.bvh")
    assert motion.skeleton.names == ("Hips", "LeftUpLeg", "LeftLeg", "Spine")
    np.testing.assert_array_equal(motion.skeleton.end_site_offsets, [[0, -38, 0], [0, 50, 0]])
    assert motion.warnings == (
        "line 14: read 'End Site4' as 'End Site'",
        "line 24: read 'End Site12' as 'End Site'",
    )
    np.testing.assert_allclose(positions(motion)[0, 2], [9, 50, 0])


@pytest.mark.parametrize("word", ["SiteX", "Site4b", "Sites", "4"])
def test_end_followed_by_other_words_is_still_refused_with_the_line(word):
    text = (QUIRKS / "end_site_numbered.bvh").read_text().replace("End Site4", f"End {word}")
    with pytest.raises(BVHError, match=f"expected 'End Site' but found 'End {word}'") as caught:
        read(text)
    assert caught.value.line == 14


def test_makehuman_benchmark_places_every_joint_as_transform_composing_readers_do():
    """MakeHuman writes every joint's position values as displacements from its rest place, the
    root's included (its values are near minus its OFFSET): the root stands at the origin."""
    motion = read(QUIRKS / "makehuman_benchmark_like.bvh")
    assert "(the root's too)" in motion.warnings[0]
    ours = positions(motion)
    np.testing.assert_allclose(ours[0, 0], [-0.057191, -0.030466, -0.003066], atol=1e-6)
    np.testing.assert_allclose(ours, reference_positions(_as_displacements(motion)), atol=1e-9)
    np.testing.assert_allclose(ours[1, 0] - ours[0, 0], [0.01, 0, 0], atol=1e-9)


def _as_displacements(motion):
    """The motion with its frames back as written in a displacement file (values minus OFFSET on
    every position channel), for `reference_positions` to add the OFFSET as such readers do."""
    sk, frames = motion.skeleton, motion.frames.copy()
    for j, channels in enumerate(sk.channels):
        for k, c in enumerate(channels):
            if c.endswith("position"):
                frames[:, int(sk.channel_starts[j]) + k] -= sk.offsets[j, "XYZ".index(c[0])]
    return motion.with_frames(frames)


@pytest.mark.parametrize("name", sorted(p.name for p in RIGS.glob("*.bvh")))
def test_forward_kinematics_agrees_with_transform_composing_readers_on_every_rig(name):
    """Where readers agree among themselves, so do we: every joint relative to the root on every
    third-party rig file, and world positions where the root's OFFSET is zero."""
    motion = read(RIGS / name)
    motion = motion.with_frames(motion.frames[:: max(motion.n_frames // 5, 1)])
    ours = positions(motion)
    theirs = reference_positions(_as_displacements(motion))
    scale = float(np.abs(ours).max())
    np.testing.assert_allclose(ours - ours[:, :1], theirs - theirs[:, :1], atol=1e-9 * scale)
    if not motion.skeleton.offsets[0].any():
        np.testing.assert_allclose(ours, theirs, atol=1e-9 * scale)
