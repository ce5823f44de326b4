"""Property test: damaged BVH files give a valid `Motion` or a `BVHError`, never anything else,
each within a second of CPU time.

Valid files (hand-written, random skeletons with CRLF and tabs, a nested 6-channel skeleton, a
UI-PRMD repetition, a gzip-compressed file) are truncated, lose or repeat tokens, get bytes
flipped, numbers replaced by huge or odd ones and junk lines inserted. ``FUZZ_EXAMPLES`` (default
8400: with tests/webapp/test_upload_fuzz.py the suite runs over 10,000 fuzz cases) is the total
number of examples, shared by the mutation families; `make fuzz` raises it.
"""

import gzip
import math
import os
import random
import re
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analysis.bvh import BVHError, dumps, read
from analysis.kinematics import positions
from tests.analysis import bvh_cases as bc

FUZZ_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "8400"))
FAMILIES = ("truncate", "delete", "duplicate", "flip", "huge", "junk", "mixed")
PER_FAMILY = math.ceil(FUZZ_EXAMPLES / len(FAMILIES))
TIME_LIMIT_S = 1.0
_SPLIT = re.compile(rb"(\s+)")
_NUMBER = re.compile(rb"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
HUGE = [
    b"1e308", b"-1.7976931348623157e308", b"1e309", b"-1e400", b"9" * 400, b"1" * 5000,
    b"0." + b"0" * 400 + b"1", b"4e-320", b"123456789012345678901234567890", b"99999999999999999",
    b"nan", b"-inf", b"1e", b"--1", b"1e+", b"0x1F", b".", b"1.2.3", b"+", b"1_000",
]  # fmt: skip
JUNK = [
    b"}", b"{", b"ROOT Extra", b"JOINT", b"End Site", b"MOTION", b"HIERARCHY", b"Frames: 2",
    b"Frames: 99999999999", b"Frame Time: 0", b"CHANNELS 6 Xposition", b"OFFSET 1 2", b"",
    b"\t \r", b"1 2 3", b"\x00\xff\xfe", "é ü ²".encode(),
]  # fmt: skip


def _ui_prmd_rep() -> bytes:
    motion = read(Path("data/ui-prmd/reps/m01_s01_e01.bvh.gz"))
    return dumps(motion.with_frames(motion.frames[:3])).encode()


def _bases() -> list[bytes]:
    rng = np.random.default_rng(2024)
    random_small = bc.random_case(rng, 6, 3, position_prob=0.5)
    return [
        bc.SMALL.encode(),
        random_small.text(newline="\r\n", indent="\t", sep="\t").encode(),
        bc.bandai_like_case(rng, 2).text(indent="  ").encode(),
        _ui_prmd_rep(),
        gzip.compress(bc.SMALL.encode()),
    ]


BASES = _bases()


def tokens(data: bytes) -> list[bytes]:
    return [t for t in _SPLIT.split(data) if t]


# Positions come from a Random seeded by hypothesis: uniform over the file, where hypothesis'
# own integers (and st.randoms) favour small values, the first bytes, the HIERARCHY keyword.
TYPICAL_BYTES = b"0123456789.-+eE \t\n\r{}xX#"


def truncate(data: bytes, draw, rnd) -> bytes:
    return data[: rnd.randint(0, len(data))]


def delete_token(data: bytes, draw, rnd) -> bytes:
    parts = tokens(data)
    if not parts:
        return data
    k = rnd.randrange(len(parts))
    return b"".join(parts[:k] + parts[k + 1 :])


def duplicate_token(data: bytes, draw, rnd) -> bytes:
    parts = tokens(data)
    if not parts:
        return data
    k = rnd.randrange(len(parts))
    return b"".join([*parts[: k + 1], b" ", *parts[k:]])


def flip_bytes(data: bytes, draw, rnd) -> bytes:
    if not data:
        return data
    out = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        typical = draw(st.booleans())
        value = rnd.choice(TYPICAL_BYTES) if typical else draw(st.integers(0, 255))
        out[rnd.randrange(len(out))] = value
    return bytes(out)


def huge_number(data: bytes, draw, rnd) -> bytes:
    parts = tokens(data)
    numbers = [k for k, t in enumerate(parts) if _NUMBER.match(t)]
    if not numbers:
        return data
    parts[rnd.choice(numbers)] = draw(
        st.sampled_from(HUGE)
        | st.integers(-(10**40), 10**40).map(lambda v: str(v).encode())
        | st.floats(allow_nan=True, allow_infinity=True).map(lambda v: repr(v).encode())
    )
    return b"".join(parts)


def junk_line(data: bytes, draw, rnd) -> bytes:
    lines = data.split(b"\n")
    k = rnd.randint(0, len(lines))
    junk = draw(st.sampled_from(JUNK) | st.binary(max_size=24))
    return b"\n".join([*lines[:k], junk, *lines[k:]])


MUTATORS = {
    "truncate": truncate,
    "delete": delete_token,
    "duplicate": duplicate_token,
    "flip": flip_bytes,
    "huge": huge_number,
    "junk": junk_line,
}


def mixed(data: bytes, draw, rnd) -> bytes:
    for name in draw(st.lists(st.sampled_from(sorted(MUTATORS)), min_size=2, max_size=4)):
        data = MUTATORS[name](data, draw, rnd)
    return data


MUTATORS["mixed"] = mixed


def mutate(family: str, data) -> bytes:
    base = data.draw(st.sampled_from(BASES))
    if base[:2] == b"\x1f\x8b" and family not in ("truncate", "flip"):
        base = gzip.decompress(base)  # token edits of compressed bytes only test zlib
    rnd = random.Random(data.draw(st.integers(0, 2**32 - 1)))
    return MUTATORS[family](base, data.draw, rnd)


def outcome(data: bytes) -> str:
    """'motion' or 'error'; fails on any other exception or an inconsistent result."""
    try:
        motion = read(data)
    except BVHError as error:
        assert isinstance(error, ValueError)
        assert error.reason
        if error.line is not None and data[:2] != b"\x1f\x8b":
            assert 1 <= error.line <= data.count(b"\n") + 2, (error.line, str(error))
        return "error"
    sk = motion.skeleton
    n_joints = len(sk.names)
    assert motion.frames.shape == (motion.n_frames, sk.n_channels)
    assert np.isfinite(motion.frames).all()
    assert motion.frame_time > 0
    assert sk.parents.shape == (n_joints,) and sk.offsets.shape == (n_joints, 3)
    assert positions(motion).shape == (motion.n_frames, n_joints, 3)
    return "motion"


@pytest.fixture(scope="module", autouse=True)
def warm_up():
    """Load the compiled scanner and kinematics (and their error paths) before timing."""
    for base in BASES:
        outcome(base)
        outcome(base[: len(base) - 3])
        outcome(base.replace(b"0.0", b"x", 1))


def test_bases_are_valid():
    assert [outcome(base) for base in BASES] == ["motion"] * len(BASES)


@pytest.mark.parametrize("family", FAMILIES)
def test_mutated_files_give_a_motion_or_a_bvh_error(family):
    seen: Counter[str] = Counter()
    slowest = [0.0, 0.0]  # CPU, wall

    @settings(
        max_examples=PER_FAMILY,
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(st.data())
    def run(data):
        mutated = mutate(family, data)
        cpu, wall = time.thread_time(), time.perf_counter()
        seen[outcome(mutated)] += 1
        cpu, wall = time.thread_time() - cpu, time.perf_counter() - wall
        slowest[:] = max(slowest[0], cpu), max(slowest[1], wall)
        # CPU time: the machine running the suite may be shared (wall time is printed too).
        assert cpu < TIME_LIMIT_S, f"{cpu:.3f} s CPU, {wall:.3f} s wall"

    run()
    print(f"\n{family}: {dict(seen)} slowest {slowest[0]:.3f} s CPU / {slowest[1]:.3f} s wall")
    assert sum(seen.values()) >= PER_FAMILY
    assert seen["error"] > 0, seen
    if family in ("flip", "huge", "duplicate", "junk"):
        assert seen["motion"] > 0, seen  # some damage leaves a readable file
    assert slowest[0] < TIME_LIMIT_S


def test_caller_caps_refuse_before_allocating():
    """Uploads pass tighter caps than the defaults: a bomb stops at the decompressed-size cap and
    a declared frame block above the value cap is refused by its header, with the reason."""
    text = bc.SMALL.encode()
    motion = read(text)
    values = motion.n_frames * motion.skeleton.n_channels
    assert read(text, max_values=values).n_frames == motion.n_frames
    with pytest.raises(BVHError, match=f"at most {values - 1} are accepted"):
        read(text, max_values=values - 1)
    bomb = gzip.compress(text + b"\n" * (3 << 20))
    with pytest.raises(BVHError, match="larger than 2 MiB"):
        read(bomb, max_bytes=2 << 20)
    assert read(bomb, max_bytes=4 << 20).n_frames == motion.n_frames
