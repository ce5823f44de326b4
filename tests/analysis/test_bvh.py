"""BVH reading and writing: accepted layouts, exact values, round trips and every malformed case,
each reported as a `BVHError` naming the line and the problem."""

import gzip
import io
import re
import time
from pathlib import Path

import numpy as np
import pytest

from analysis.bvh import BVHError, Motion, Skeleton, dumps, read, write
from analysis.kinematics.forward_kinematics import end_site_positions, positions
from tests.analysis import bvh_cases as bc

REPS = Path("data/ui-prmd/reps")
S = bc.SMALL
SMALL_FRAMES = np.array(
    [
        [1.0, 90.0, 2.0, 10.0, 0.0, 0.0, 45.0, 0.0, 0.0],
        [1.5, 90.5, 2.5, 20.0, 0.0, 0.0, 50.0, 0.0, 0.0],
        [2.0, 91.0, 3.0, 30.0, 0.0, 0.0, 55.0, 0.0, 0.0],
    ]
)


def assert_small(motion: Motion) -> None:
    sk = motion.skeleton
    assert sk.names == ("Hips", "Knee")
    assert sk.parents.tolist() == [-1, 0]
    np.testing.assert_array_equal(sk.offsets, [[0, 0, 0], [0, -40, 0]])
    assert sk.channels == (
        ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"),
        ("Zrotation", "Xrotation", "Yrotation"),
    )
    assert sk.end_site_parents.tolist() == [1]
    np.testing.assert_array_equal(sk.end_site_offsets, [[0, -40, 0]])
    np.testing.assert_array_equal(motion.frames, SMALL_FRAMES)
    assert motion.frames.dtype == np.float64
    assert motion.frame_time == pytest.approx(0.0333333, abs=1e-12)
    assert motion.fps == pytest.approx(1 / 0.0333333)


def assert_same_as_case(motion: Motion, case: bc.Case, atol: float = 0.0) -> None:
    sk = motion.skeleton
    assert sk.names == case.names
    np.testing.assert_array_equal(sk.parents, case.parents)
    np.testing.assert_allclose(sk.offsets, case.offsets, rtol=1e-13, atol=atol)
    assert sk.channels == case.channels
    assert sk.end_site_parents.tolist() == [p for p, _ in case.end_sites]
    np.testing.assert_allclose(
        sk.end_site_offsets.reshape(-1, 3),
        [o for _, o in case.end_sites] or np.zeros((0, 3)),
        atol=max(atol, 1e-12),
    )
    np.testing.assert_allclose(motion.frames, case.values, rtol=1e-13, atol=atol)
    assert motion.frame_time == pytest.approx(case.frame_time, abs=max(atol, 1e-15))


# ---------------------------------------------------------------- accepted input


def test_small_file_fields():
    assert_small(read(S))


def test_every_kind_of_source_gives_the_same_motion(tmp_path):
    plain, packed = tmp_path / "a.bvh", tmp_path / "a.bvh.gz"
    plain.write_text(S)
    packed.write_bytes(gzip.compress(S.encode()))
    sources = [
        S,
        S.encode(),
        bytearray(S.encode()),
        gzip.compress(S.encode()),
        str(plain),
        plain,
        str(packed),
        packed,
        io.BytesIO(S.encode()),
        io.StringIO(S),
        io.BytesIO(gzip.compress(S.encode())),
    ]
    for source in sources:
        assert_small(read(source))
    with plain.open("rb") as binary, plain.open() as text, gzip.open(packed) as unpacked:
        for handle in (binary, text, unpacked):
            assert_small(read(handle))


def test_gzip_is_detected_by_content_not_by_name(tmp_path):
    odd = tmp_path / "compressed_but_named.bvh"
    odd.write_bytes(gzip.compress(S.encode()))
    assert_small(read(odd))


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
@pytest.mark.parametrize(
    ("indent", "sep"), [("\t", " "), ("  ", "\t"), ("", " \t  "), ("\t\t", "\t")]
)
def test_line_ends_tabs_and_spacing(newline, indent, sep):
    case = bc.random_case(np.random.default_rng(7), n_joints=6, n_frames=4)
    text = case.text(newline=newline, indent=indent, sep=sep)
    assert ("\r\n" in text) == (newline == "\r\n")
    assert_same_as_case(read(text), case)
    assert_same_as_case(read(text.encode()), case)


@pytest.mark.parametrize("seed", range(8))
def test_random_skeletons_any_channel_order_and_count(seed):
    rng = np.random.default_rng(seed)
    case = bc.random_case(rng, n_joints=int(rng.integers(1, 30)), n_frames=int(rng.integers(1, 12)))
    assert_same_as_case(read(case.text()), case)


def test_random_cases_cover_the_layouts_the_issue_names():
    rng = np.random.default_rng(0)
    cases = [bc.random_case(rng, 12, 2) for _ in range(8)]
    channels = [c for case in cases for c in case.channels[1:]]
    counts = {len(c) for c in channels}
    assert {3, 6} <= counts and counts - {3, 6}, "3, 6 and partial channel counts"
    orders = {"".join(n[0] for n in c if n.endswith("rotation")) for c in channels}
    assert set(bc.TAIT_BRYAN_ORDERS) <= orders, "all six Tait-Bryan orders"
    assert any(n.endswith("position") for c in channels for n in c), "positions on non-root joints"
    assert any(case.end_sites for case in cases)


def test_six_channels_on_every_joint_and_a_nested_static_root():
    case = bc.bandai_like_case(np.random.default_rng(1), n_frames=5)
    motion = read(case.text())
    assert_same_as_case(motion, case)
    assert all(len(c) == 6 for c in motion.skeleton.channels)
    assert motion.skeleton.parents[:2].tolist() == [-1, 0]


def test_exponents_signs_and_bare_points():
    case = bc.arm_case([0.0])
    tokens = [
        "1e-3",
        "2E+1",
        "-3.5e2",
        "+4E-0",
        ".5",
        "5.",
        "1.5E+01",
        "-0",
        "7e0",
        "0.25e+2",
        "3",
        "-2",
    ]
    case = bc.Case(
        case.joints, case.end_sites, [tokens], offset_tokens={1: ("1e-3", "-3E+1", "+0.0e0")}
    )
    motion = read(case.text())
    expected = [0.001, 20.0, -350.0, 4.0, 0.5, 5.0, 15.0, 0.0, 7.0, 25.0, 3.0, -2.0]
    np.testing.assert_array_equal(motion.frames, [expected])
    np.testing.assert_array_equal(motion.skeleton.offsets[1], [0.001, -30.0, 0.0])


def test_many_digits_are_parsed_to_the_nearest_double():
    rng = np.random.default_rng(3)
    values = np.concatenate([rng.normal(0, 100, 300), rng.normal(0, 1e-7, 50), [1e300, -2.5e-300]])
    text = bc.flat_skeleton_text(1, n_frames=1, channels=3).rsplit("MOTION", 1)[0]
    body = "\n".join(" ".join(repr(float(v)) for v in values[k : k + 3]) for k in range(0, 351, 3))
    motion = read(f"{text}MOTION\nFrames: {len(values) // 3}\nFrame Time: 0.01\n{body}\n")
    np.testing.assert_allclose(motion.frames.ravel(), values[: 3 * (len(values) // 3)], rtol=1e-15)


def test_zero_frames():
    text = S.split("Frames:")[0] + "Frames: 0\nFrame Time: 0.01\n"
    motion = read(text)
    assert motion.frames.shape == (0, 9)
    assert positions(motion).shape == (0, 2, 3)


def test_blank_lines_and_trailing_spaces_in_the_frame_block():
    lines = S.splitlines()
    text = "\n".join(
        [*lines[:18], "", lines[18] + "   ", "  ", lines[19] + "\t", lines[20], "", ""]
    )
    np.testing.assert_array_equal(read(text).frames, SMALL_FRAMES)


def test_byte_order_mark_and_a_joint_called_motion():
    assert_small(read(("\ufeff" + S).encode()))
    renamed = read(S.replace("Knee", "MOTION_sensor"))
    assert renamed.skeleton.names == ("Hips", "MOTION_sensor")


# ---------------------------------------------------------------- round trip


@pytest.mark.parametrize("seed", range(6))
def test_read_dumps_read_keeps_every_value(seed):
    rng = np.random.default_rng(100 + seed)
    case = bc.random_case(rng, n_joints=int(rng.integers(1, 25)), n_frames=int(rng.integers(0, 20)))
    first = read(case.text())
    again = read(dumps(first))
    assert_same_as_case(again, case, atol=1e-6)


def test_round_trip_of_a_nested_six_channel_skeleton():
    case = bc.bandai_like_case(np.random.default_rng(5), n_frames=7)
    assert_same_as_case(read(dumps(read(case.text()))), case, atol=1e-6)


@pytest.mark.parametrize("name", ["out.bvh.gz", "out.bvh"])
def test_write_and_read_back(tmp_path, name):
    original = read(REPS / "m01_s01_e01.bvh.gz")
    path = tmp_path / name
    write(original, path)
    assert (path.read_bytes()[:2] == b"\x1f\x8b") == name.endswith(".gz")
    back = read(path)
    assert back.skeleton.names == original.skeleton.names
    assert back.skeleton.channels == original.skeleton.channels
    np.testing.assert_array_equal(back.skeleton.parents, original.skeleton.parents)
    np.testing.assert_allclose(back.skeleton.offsets, original.skeleton.offsets, atol=1e-6)
    np.testing.assert_allclose(back.frames, original.frames, atol=1e-6)
    assert back.frame_time == pytest.approx(original.frame_time, abs=1e-8)


def test_dumps_writes_frames_in_the_order_of_a_code_built_skeleton():
    """Joints listed breadth-first (a, b, c, d with d under b) are written depth-first
    (a, b, d, c): the frame columns must move with them."""
    rot = ("Zrotation", "Xrotation", "Yrotation")
    skeleton = Skeleton(
        names=("a", "b", "c", "d"),
        parents=np.array([-1, 0, 0, 1]),
        offsets=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
        channels=(("Xposition", "Yposition", "Zposition", *rot), rot, rot, rot),
        end_site_parents=np.array([2, 3]),
        end_site_offsets=np.array([[0.0, 2, 0], [2.0, 0, 0]]),
    )
    motion = Motion(skeleton, np.arange(30, dtype=float).reshape(2, 15), 0.1)
    back = read(dumps(motion))
    assert back.skeleton.names == ("a", "b", "d", "c")
    np.testing.assert_array_equal(back.frames[:, 9:12], motion.frames[:, 12:15])
    np.testing.assert_array_equal(back.frames[:, 12:15], motion.frames[:, 9:12])
    np.testing.assert_allclose(positions(back)[:, [0, 1, 3, 2]], positions(motion), atol=1e-9)
    np.testing.assert_allclose(
        end_site_positions(back)[:, ::-1], end_site_positions(motion), atol=1e-6
    )


# ---------------------------------------------------------------- malformed input

TWO_ROOTS = S.replace(
    "}\nMOTION", "}\nROOT Other\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION"
)
FRAMES_LINE, TIME_LINE, FIRST = 17, 18, bc.SMALL_FIRST_FRAME_LINE
ROW = "1 2 3 4 5 6 7 8 9"
BAD = [
    ("no HIERARCHY", S.replace("HIERARCHY\n", ""), 1, r"does not start with HIERARCHY"),
    ("junk before HIERARCHY", "hello\n" + S, 1, r"does not start with HIERARCHY"),
    ("no MOTION", S.split("MOTION")[0], 15, r"no MOTION section"),
    ("MOTION line deleted", bc.edit_line(S, 16, None), 20, r"no MOTION section"),
    (
        "missing closing brace",
        bc.edit_line(S, 14, None),
        15,
        r"unbalanced braces: joint 'Hips' \(line 2\) is never closed",
    ),
    (
        "missing inner brace",
        bc.edit_line(S, 13, None),
        15,
        r"unbalanced braces: joint 'Hips'|expected '}'",
    ),
    ("extra closing brace", bc.insert_line(S, 15, "}"), 16, r"unbalanced braces: one '}' too many"),
    ("missing opening brace", bc.edit_line(S, 7, None), 7, r"expected '\{' but found 'OFFSET'"),
    (
        "unknown channel",
        S.replace("3 Zrotation Xrotation", "3 Wrotation Xrotation"),
        9,
        r"unknown channel 'Wrotation'",
    ),
    (
        "channel twice",
        S.replace("3 Zrotation Xrotation", "3 Zrotation Zrotation"),
        9,
        r"declared twice",
    ),
    (
        "channel count 7",
        S.replace("CHANNELS 3", "CHANNELS 7"),
        9,
        r"CHANNELS count must be 0 to 6, found '7'",
    ),
    (
        "fewer channel names",
        S.replace("3 Zrotation Xrotation Yrotation", "3 Zrotation Xrotation"),
        10,
        r"unknown channel 'End'",
    ),
    ("joint without name", S.replace("JOINT Knee", "JOINT"), 6, r"a joint needs a name"),
    ("joint without OFFSET", bc.edit_line(S, 8, None), 13, r"joint 'Knee' has no OFFSET"),
    (
        "OFFSET not a number",
        S.replace("OFFSET 0.0 -40.0 0.0", "OFFSET 0.0 abc 0.0", 1),
        8,
        r"OFFSET 'abc' is not a number",
    ),
    (
        "OFFSET NaN",
        S.replace("OFFSET 0.0 -40.0 0.0", "OFFSET 0.0 nan 0.0", 1),
        8,
        r"OFFSET is not finite",
    ),
    ("several ROOTs", TWO_ROOTS, 16, r"several ROOTs"),
    (
        "too few values",
        bc.edit_line(S, FIRST + 1, "1 2 3"),
        FIRST + 1,
        r"frame line has 3 values but the skeleton has 9 channels",
    ),
    (
        "too many values",
        bc.edit_line(S, FIRST, ROW + " 10"),
        FIRST,
        r"frame line has 10 values but the skeleton has 9 channels",
    ),
    (
        "fewer frames than declared",
        bc.edit_line(S, FIRST + 2, None),
        FIRST + 2,
        r"3 frames declared but 2 found",
    ),
    # "more frames than declared" now loads with a warning: tests/analysis/test_bvh_quirks.py.
    (
        "non-numeric value",
        bc.edit_line(S, FIRST + 1, "1 2 3 4 abc 6 7 8 9"),
        FIRST + 1,
        r"'abc' is not a number",
    ),
    (
        "two points",
        bc.edit_line(S, FIRST, "1 2 3 4 1.2.3 6 7 8 9"),
        FIRST,
        r"'1.2.3' is not a number",
    ),
    (
        "comma decimal",
        bc.edit_line(S, FIRST, "1 2 3 4 1,5 6 7 8 9"),
        FIRST,
        r"'1,5' is not a number",
    ),
    (
        "bare sign",
        bc.edit_line(S, FIRST + 2, "1 2 3 4 - 6 7 8 9"),
        FIRST + 2,
        r"'-' is not a number",
    ),
    (
        "NaN value",
        bc.edit_line(S, FIRST, "1 2 3 4 NaN 6 7 8 9"),
        FIRST,
        r"'NaN' is not a finite number",
    ),
    (
        "infinite value",
        bc.edit_line(S, FIRST, "1 2 3 4 -inf 6 7 8 9"),
        FIRST,
        r"'-inf' is not a finite number",
    ),
    (
        "overflowing value",
        bc.edit_line(S, FIRST, "1 2 3 4 1e999 6 7 8 9"),
        FIRST,
        r"'1e999' is not a finite number",
    ),
    (
        "frame time zero",
        bc.edit_line(S, TIME_LINE, "Frame Time: 0"),
        TIME_LINE,
        r"Frame Time must be positive",
    ),
    (
        "frame time negative",
        bc.edit_line(S, TIME_LINE, "Frame Time: -0.01"),
        TIME_LINE,
        r"Frame Time must be positive",
    ),
    (
        "frame time NaN",
        bc.edit_line(S, TIME_LINE, "Frame Time: nan"),
        TIME_LINE,
        r"Frame Time is not finite",
    ),
    (
        "frame time text",
        bc.edit_line(S, TIME_LINE, "Frame Time: fast"),
        TIME_LINE,
        r"Frame Time 'fast' is not a number",
    ),
    ("no Frame Time", bc.edit_line(S, TIME_LINE, None), TIME_LINE, r"expected 'Frame Time:'"),
    ("no Frames", bc.edit_line(S, FRAMES_LINE, None), FRAMES_LINE, r"expected 'Frames:'"),
    (
        "frame count negative",
        bc.edit_line(S, FRAMES_LINE, "Frames: -3"),
        FRAMES_LINE,
        r"'-3' is not a whole number",
    ),
    (
        "frame count fraction",
        bc.edit_line(S, FRAMES_LINE, "Frames: 2.5"),
        FRAMES_LINE,
        r"'2.5' is not a whole number",
    ),
    (
        "frame count superscript",
        bc.edit_line(S, FRAMES_LINE, "Frames: ²"),
        FRAMES_LINE,
        r"'²' is not a whole number",
    ),
    (
        "no channels at all",
        re.sub(r"CHANNELS \d( \w+)*", "CHANNELS 0", S),
        1,
        r"declares no channels",
    ),
]


@pytest.mark.parametrize(("text", "line", "message"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_malformed_input_names_the_line_and_the_problem(text, line, message):
    with pytest.raises(BVHError, match=message) as caught:
        read(text)
    error = caught.value
    assert isinstance(error, ValueError)
    assert error.line == line, str(error)
    assert str(error).startswith(f"line {line}: ")


LIMITS = [
    (
        "frame count absurd",
        bc.edit_line(S, FRAMES_LINE, "Frames: 999999999999"),
        FRAMES_LINE,
        r"999999999999 frames declared; at most",
    ),
    (
        "frame count with 5000 digits",
        bc.edit_line(S, FRAMES_LINE, "Frames: " + "9" * 5000),
        FRAMES_LINE,
        r"\(5000 digits\) frames declared",
    ),
    (
        "frame count allowed but the file is short",
        bc.edit_line(S, FRAMES_LINE, "Frames: 4000000"),
        FRAMES_LINE,
        r"4000000 frames declared but the file is far too short",
    ),
    (
        "channel count with 5000 digits",
        S.replace("CHANNELS 3", "CHANNELS " + "3" * 5000),
        9,
        r"CHANNELS count must be 0 to 6",
    ),
    ("1025 joints", bc.flat_skeleton_text(1025), 5 * 1024 + 1, r"more than 1024 joints"),
    ("200000 joints", bc.flat_skeleton_text(200_000), 1, r"hierarchy is larger than 2 MiB"),
    (
        "10000 nested levels",
        bc.deep_chain_text(10_000),
        5 + 4 * 255 + 1,
        r"nested deeper than 256 levels",
    ),
]


@pytest.mark.parametrize(
    ("text", "line", "message"), [b[1:] for b in LIMITS], ids=[b[0] for b in LIMITS]
)
def test_limits_fail_fast_without_memory_or_recursion_blow_up(text, line, message):
    read(bc.SMALL)  # compiled scanner loaded before timing
    # Processor time, not wall time: a blow-up spends it, a busy machine does not add to it.
    start = time.process_time()
    with pytest.raises(BVHError, match=message) as caught:
        read(text.encode())
    assert time.process_time() - start < 0.5
    assert caught.value.line == line


def test_deepest_allowed_chain_reads_and_writes():
    motion = read(bc.deep_chain_text(256))
    assert len(motion.skeleton.names) == 256
    assert motion.skeleton.parents.tolist() == list(range(-1, 255))
    assert read(dumps(motion)).skeleton.names == motion.skeleton.names
    np.testing.assert_allclose(positions(motion)[0, -1], [0, 255, 0])


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (lambda b: b[: len(b) // 2], r"gzip data is truncated"),
        (lambda b: b[:20] + bytes(255 - x for x in b[20:40]) + b[40:], r"gzip data is damaged"),
    ],
)
def test_damaged_gzip(damage, message):
    with pytest.raises(BVHError, match=message):
        read(damage(gzip.compress(S.encode() * 20)))


def test_ui_prmd_reps_all_read():
    for path in sorted(REPS.glob("*.bvh.gz")):
        motion = read(path)
        assert motion.frames.shape == (motion.n_frames, motion.skeleton.n_channels)
        assert len(motion.skeleton.names) == 22
        assert motion.fps == pytest.approx(30.0, rel=1e-3)
