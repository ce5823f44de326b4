"""Malformed capture files of every format (truncated, NaN, wrong columns, empty, huge numbers,
text in numbers, one joint only) end in a one-line error of the BVH error family
(`CaptureFileError` is a `BVHError`), never another exception; a file that still reads gives a
motion with finite values. Hypothesis, derandomised (a fixed seed); C3D files, read by a child
process each, get fewer examples."""

from __future__ import annotations

import os
import re
import tempfile
from functools import cache
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analysis.bvh import BVHError
from analysis.sources import read_recording
from tests.analysis.test_sources_formats import standing
from tests.capture_samples import SUFFIX, write_layout

EXAMPLES = int(os.environ.get("CAPTURE_FUZZ_EXAMPLES", "60"))  # per text format
C3D_EXAMPLES = max(3, EXAMPLES // 20)
TEXT_LAYOUTS = ("kinect_wide", "kinect_long", "azure", "trc", "mediapipe")
_NUMBER = re.compile(rb"-?\d+\.\d+")
SWAPS = [b"nan", b"1e309", b"-1e300", b"abc", b"", b"1.2.3", b"9" * 400, b"\x00", b"inf"]


@cache
def base(layout: str) -> bytes:
    with tempfile.TemporaryDirectory() as folder:
        return write_layout(layout, standing(12), 30.0, Path(folder)).read_bytes()


def check(name: str, content: bytes) -> None:
    try:
        recording = read_recording(name, content)
    except BVHError as error:
        text = str(error)
        assert text and "\n" not in text and "Traceback" not in text
        return
    assert np.all(np.isfinite(recording.motion.frames))


def mutate(content: bytes, data: st.DataObject) -> bytes:
    kind = data.draw(st.sampled_from(("truncate", "number", "line", "columns", "one", "empty")))
    lines = content.split(b"\n")
    if kind == "truncate":
        return content[: data.draw(st.integers(0, len(content)))]
    if kind == "number":
        spans = [m.span() for m in _NUMBER.finditer(content)]
        for _ in range(data.draw(st.integers(1, 5))):
            a, b = data.draw(st.sampled_from(spans))
            swap = data.draw(st.sampled_from(SWAPS))
            content = content[:a] + swap + content[b:]
            spans = [m.span() for m in _NUMBER.finditer(content)] or [(0, 0)]
        return content
    if kind == "line":
        k = data.draw(st.integers(0, len(lines) - 1))
        return b"\n".join(lines[:k] + lines[k + 1 :])
    if kind == "columns":  # the header's columns shuffled or renamed
        header = lines[0].split(b",")
        shuffled = data.draw(st.permutations(header))
        return b"\n".join([b",".join(shuffled), *lines[1:]])
    if kind == "one":  # one joint only: keep the first few columns / rows of one name
        keep = data.draw(st.integers(1, 6))
        return b"\n".join(b",".join(line.split(b",")[:keep]) for line in lines)
    return b""


@settings(max_examples=EXAMPLES * len(TEXT_LAYOUTS), derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])  # fmt: skip
@given(layout=st.sampled_from(TEXT_LAYOUTS), data=st.data())
def test_malformed_text_files_give_one_line_errors(layout, data):
    check(f"take{SUFFIX[layout]}", mutate(base(layout), data))


@settings(max_examples=C3D_EXAMPLES, derandomize=True, deadline=None)
@given(data=st.data())
def test_damaged_c3d_files_give_one_line_errors(data):
    content = bytearray(base("c3d"))
    # Flipped bytes can send ezc3d into long reads (up to the child's time limit): the suite
    # truncates; more examples (CAPTURE_FUZZ_EXAMPLES) flip bytes too.
    if C3D_EXAMPLES <= 3 or data.draw(st.booleans()):
        content = content[: data.draw(st.integers(0, len(content)))]
    else:
        for _ in range(data.draw(st.integers(1, 12))):
            content[data.draw(st.integers(0, len(content) - 1))] = data.draw(st.integers(0, 255))
    check("take.c3d", bytes(content))


def test_every_kind_of_empty_or_one_joint_file_is_refused():
    for name in ("a.csv", "a.json", "a.trc", "a.c3d"):
        for content in (b"", b"   \n", b"x"):
            check(name, content)
    one_joint = b"Time,Head_X,Head_Y,Head_Z\n0,0,1.6,0\n0.033,0,1.6,0\n0.066,0,1.6,0\n"
    try:
        read_recording("one.csv", one_joint)
    except BVHError as error:
        assert "left shoulder" in str(error)
    else:
        raise AssertionError("a file with only the head was read")
