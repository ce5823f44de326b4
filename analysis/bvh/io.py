"""Reading and writing BVH motion capture (``.bvh`` and gzip-compressed ``.bvh.gz``).

``read`` accepts a path, raw bytes or the text itself and returns a `Motion`: the skeleton
(joint names in file order, parent indices, offsets, per-joint channel lists as declared) and the
frame values as one (F, C) float64 array. Malformed input raises `BVHError` (a ``ValueError``)
naming the line and the problem. The frame block is parsed by a compiled scanner; the hierarchy,
a few kilobytes at most, by an iterative token walker.

Files that common readers open but that bend the format load with ``Motion.warnings`` saying what
was bent (the reader never warns about a clean file):

- a first joint declared ``JOINT`` instead of ``ROOT``; words after ``End Site``; an unknown
  keyword line inside a joint (skipped); see `analysis.bvh.header`;
- more frame lines than ``Frames:`` declares: every well-formed line is kept (Blender and PyMO read
  them all; a count written before the take ended is the usual cause);
- position channels on joints other than the root. Two conventions exist: the values *replace*
  the OFFSET (Bandai-Namco, MotionBuilder and most exporters writing 6 channels per joint: the
  values equal the OFFSET when bones do not stretch) or are *added* to it (some MakeHuman/Blender
  exports: the values stay near zero). `Motion.frames` always holds the replacing convention, the
  one `analysis.kinematics` uses. The reader chooses per file: *added* when the values' mean
  magnitude is under a quarter of their mean distance from the OFFSET and under half the OFFSET's
  mean magnitude (values near zero, offsets clearly not), and then adds the OFFSET to those
  columns, and the root's OFFSET to the root's (that exporter writes displacements from the rest
  place for every joint: MakeHuman's ``benchmark.bvh``); otherwise *replacing*, unchanged.
  Both give a warning. Where the OFFSETs are zero the two conventions agree.

Malformed input still raises `BVHError` with the line.
"""

from __future__ import annotations

import gzip
import io
import os
import re
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np
import numpy.typing as npt

from analysis.bvh.errors import BVHError
from analysis.bvh.frames import parse_frames
from analysis.bvh.header import Hierarchy, parse_float, parse_hierarchy

__all__ = ["BVHError", "Motion", "Skeleton", "dumps", "read", "write"]

MAX_DECOMPRESSED_BYTES = 1 << 30
MAX_FRAMES = 5_000_000
MAX_VALUES = 400_000_000
MAX_HEADER_BYTES = 2 << 20
_MOTION = re.compile(rb"^[ \t]*(MOTION)(?![A-Za-z0-9_])", re.MULTILINE)
FloatArray = npt.NDArray[np.float64]
Source = str | bytes | bytearray | os.PathLike[str] | IO[bytes] | IO[str]


@dataclass(frozen=True, eq=False)
class Skeleton:
    """Joints in file order. ``offsets``: (J, 3) file units; ``parents``: (J,), -1 for the root."""

    names: tuple[str, ...]
    parents: npt.NDArray[np.int64]
    offsets: FloatArray
    channels: tuple[tuple[str, ...], ...]
    end_site_parents: npt.NDArray[np.int64]
    end_site_offsets: FloatArray

    @property
    def channel_starts(self) -> npt.NDArray[np.int64]:
        """Index of each joint's first channel in a frame row: (J,). Worked out on every read
        (a cumulative sum over J joints, microseconds): saved models pickle their skeleton, and
        a value kept on the object would have to be rebuilt when one written before is read."""
        counts = np.array([len(c) for c in self.channels], dtype=np.int64)
        return np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int64)

    @property
    def n_channels(self) -> int:
        return sum(len(c) for c in self.channels)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def children(self, joint: int) -> list[int]:
        return [int(j) for j in np.flatnonzero(self.parents == joint)]


@dataclass(frozen=True, eq=False)
class Motion:
    """A skeleton and its frames: ``frames`` (F, C) float64 in channel order, ``frame_time`` s.

    ``warnings``: what the reader bent to open the file (plain sentences, empty for a clean file).
    """

    skeleton: Skeleton
    frames: FloatArray
    frame_time: float
    warnings: tuple[str, ...] = ()

    @property
    def n_frames(self) -> int:
        return int(self.frames.shape[0])

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    @property
    def duration(self) -> float:
        return self.n_frames * self.frame_time

    def with_frames(self, frames: FloatArray, frame_time: float | None = None) -> Motion:
        """The same skeleton with other frames (e.g. a slice, a resampled or adjusted copy)."""
        time = self.frame_time if frame_time is None else frame_time
        return Motion(self.skeleton, frames, time, self.warnings)


def _load_bytes(source: Source) -> bytes:
    if isinstance(source, bytes | bytearray):
        return bytes(source)
    if hasattr(source, "read"):
        content = source.read()
        return content.encode() if isinstance(content, str) else bytes(content)
    if isinstance(source, str) and ("\n" in source or source.lstrip().startswith("HIERARCHY")):
        return source.encode("utf-8")
    return Path(source).read_bytes()


def _size_text(n_bytes: int) -> str:
    return f"{n_bytes / (1 << 30):g} GiB" if n_bytes >= 1 << 30 else f"{n_bytes / (1 << 20):g} MiB"


def _decompress(content: bytes, max_bytes: int = MAX_DECOMPRESSED_BYTES) -> bytes:
    if content[:2] != b"\x1f\x8b":
        return content
    inflater = zlib.decompressobj(wbits=31)
    try:
        # max_length stops a gzip bomb after max_bytes instead of filling memory.
        data = inflater.decompress(content, max_bytes)
    except zlib.error as error:
        raise BVHError(f"the gzip data is damaged ({error})") from None
    if inflater.unconsumed_tail:
        raise BVHError(f"the decompressed file is larger than {_size_text(max_bytes)}")
    if not inflater.eof:
        raise BVHError("the gzip data is truncated")
    return data


def _split_sections(data: bytes) -> tuple[list[str], int, int, int]:
    """Header lines (after HIERARCHY), their first line number, where MOTION ends and its line.

    Positions rather than slices: a copy of the frame block costs more than parsing the header.
    """
    start = data.find(b"HIERARCHY")
    # A UTF-8 byte order mark is what some Windows exporters put first.
    if start < 0 or data[:start].strip().removeprefix(b"\xef\xbb\xbf").strip():
        raise BVHError("the file does not start with HIERARCHY", 1)
    # MOTION must open a line: a joint may well be called "MOTION_sensor".
    found = _MOTION.search(data, start)
    if found is None:
        last_line = data.count(b"\n", 0, len(data.rstrip())) + 1
        raise BVHError("no MOTION section after the hierarchy", last_line)
    motion_at = found.start(1)
    if motion_at - start > MAX_HEADER_BYTES:
        # Tokenising a huge header would cost memory long before the joint limit is reached.
        raise BVHError("the hierarchy is larger than 2 MiB", data.count(b"\n", 0, start) + 1)
    try:
        header = data[start + len(b"HIERARCHY") : motion_at].decode("utf-8")
    except UnicodeDecodeError:
        raise BVHError("the hierarchy is not text") from None
    header_first_line = data.count(b"\n", 0, start) + 1
    motion_line = data.count(b"\n", 0, motion_at) + 1
    return header.split("\n"), header_first_line, motion_at + len(b"MOTION"), motion_line


def _header_value(data: bytes, pos: int, line: int, label: bytes) -> tuple[str, int, int]:
    """Read 'Label: value' from the first non-blank line at pos; returns (value, next pos, line)."""
    while True:
        end = data.find(b"\n", pos)
        end = len(data) if end < 0 else end
        text = data[pos:end].strip()
        if text or end == len(data):
            break
        pos, line = end + 1, line + 1
    if not text.lower().startswith(label.lower()):
        shown = text[:40].decode("utf-8", "replace")
        raise BVHError(f"expected '{label.decode()}' but found '{shown}'", line)
    return text[len(label) :].decode("utf-8", "replace").strip(), end + 1, line + 1


def _frame_header(data: bytes, start: int, motion_line: int) -> tuple[int, float, int, int]:
    """Parse 'Frames:' and 'Frame Time:' after ``start`` (the end of the MOTION keyword);
    returns (frames, frame time, offset of the first frame line, its line number)."""
    newline = data.find(b"\n", start)
    rest = newline + 1 if newline >= 0 else len(data)
    frames_text, pos, line = _header_value(data, rest, motion_line + 1, b"Frames:")
    # isascii: str.isdigit() also accepts '²', which int() rejects.
    if not (frames_text.isascii() and frames_text.isdigit()):
        raise BVHError(f"the frame count '{frames_text[:40]}' is not a whole number", line - 1)
    digits = frames_text.lstrip("0") or "0"
    # Checking the length first keeps int() away from its 4300-digit limit.
    if len(digits) > 18 or int(digits) > MAX_FRAMES:
        shown = digits if len(digits) <= 20 else f"{digits[:12]}... ({len(digits)} digits)"
        raise BVHError(f"{shown} frames declared; at most {MAX_FRAMES} are supported", line - 1)
    n_frames = int(digits)
    time_text, pos, line = _header_value(data, pos, line, b"Frame Time:")
    frame_time = parse_float(time_text, line - 1, "Frame Time")
    if frame_time <= 0:
        raise BVHError(f"Frame Time must be positive, found {time_text}", line - 1)
    return n_frames, frame_time, pos, line


def _skeleton(tree: Hierarchy) -> Skeleton:
    joints = tree.joints
    return Skeleton(
        names=tuple(j.name for j in joints),
        parents=np.array([j.parent for j in joints], dtype=np.int64),
        offsets=np.array([j.offset for j in joints], dtype=np.float64).reshape(-1, 3),
        channels=tuple(j.channels for j in joints),
        end_site_parents=np.array(tree.end_parents, dtype=np.int64),
        end_site_offsets=np.array(tree.end_offsets, dtype=np.float64).reshape(-1, 3),
    )


def _check_frame_size(n_frames: int, n_channels: int, max_values: int, line: int) -> None:
    """Refuse a declared frame block above the caller's cap before allocating it."""
    if n_frames * n_channels > max_values:
        raise BVHError(
            f"{n_frames} frames × {n_channels} channels = {n_frames * n_channels} values; "
            f"at most {max_values} are accepted",
            line,
        )


def _non_root_position_columns(skeleton: Skeleton) -> list[tuple[int, int, int]]:
    """(joint, axis, frame column) of every position channel on a joint other than the root."""
    out = []
    for joint, (start, channels) in enumerate(
        zip(skeleton.channel_starts, skeleton.channels, strict=True)
    ):
        if skeleton.parents[joint] < 0:
            continue
        for k, channel in enumerate(channels):
            if channel.endswith("position"):
                out.append((joint, "XYZ".index(channel[0]), int(start) + k))
    return out


def _add_root_offset(skeleton: Skeleton, frames: FloatArray) -> bool:
    """In a file whose exporter adds position channels to the OFFSET (MakeHuman's
    ``benchmark.bvh``: every joint's values are displacements from its rest place), the root's
    values are displacements too: add its OFFSET in place. Whether anything was added."""
    root = int(np.flatnonzero(skeleton.parents < 0)[0])
    start = int(skeleton.channel_starts[root])
    added = False
    for k, channel in enumerate(skeleton.channels[root]):
        axis_offset = skeleton.offsets[root, "XYZ".index(channel[0])]
        if channel.endswith("position") and axis_offset != 0.0:
            frames[:, start + k] += axis_offset
            added = True
    return added


def _position_convention(skeleton: Skeleton, frames: FloatArray, warnings: list[str]) -> FloatArray:
    """Frames whose non-root position channels replace the OFFSET (see the module docstring)."""
    columns = _non_root_position_columns(skeleton)
    if not columns or frames.shape[0] == 0:
        return frames
    n_joints = len({j for j, _, _ in columns})
    offsets = np.array([skeleton.offsets[j, a] for j, a, _ in columns])
    values = frames[:, [c for _, _, c in columns]]
    size = float(np.mean(np.abs(offsets)))
    as_replacing = float(np.mean(np.abs(values - offsets)))
    as_added = float(np.mean(np.abs(values)))
    if size > 1e-9 and as_added < 0.25 * as_replacing and as_added < 0.5 * size:
        frames = frames.copy()
        frames[:, [c for _, _, c in columns]] += offsets
        root_too = _add_root_offset(skeleton, frames)
        warnings.append(
            f"position channels on {n_joints} joints other than the root hold values near zero: "
            "they were read as added to each joint's OFFSET"
            + (" (the root's too)" if root_too else "")
        )
    else:
        warnings.append(
            f"position channels on {n_joints} joints other than the root were read as the "
            "joint's place relative to its parent, replacing its OFFSET"
        )
    return frames


def parse(data: bytes, *, max_values: int = MAX_VALUES) -> Motion:
    """Parse uncompressed BVH bytes; ``max_values`` caps frames × channels (memory: 8 B each)."""
    header_lines, header_line, motion_end, motion_line = _split_sections(data)
    tree = parse_hierarchy(header_lines, header_line)
    skeleton = _skeleton(tree)
    warnings = list(tree.warnings)
    n_channels = skeleton.n_channels
    if n_channels == 0:
        raise BVHError("the skeleton declares no channels", header_line)
    n_frames, frame_time, offset, data_line = _frame_header(data, motion_end, motion_line)
    # Every value takes at least one byte: a cheap bound before allocating the frame array.
    if n_frames * n_channels > len(data) - motion_end:
        raise BVHError(f"{n_frames} frames declared but the file is far too short", data_line - 2)
    _check_frame_size(n_frames, n_channels, min(max_values, MAX_VALUES), data_line - 2)
    cap = min(max_values, MAX_VALUES)
    frames = parse_frames(
        memoryview(data)[offset:],
        n_frames,
        n_channels,
        data_line,
        warnings=warnings,
        max_values=cap,
    )
    frames = _position_convention(skeleton, frames, warnings)
    return Motion(skeleton, frames, frame_time, tuple(warnings))


def read(
    source: Source,
    *,
    max_bytes: int = MAX_DECOMPRESSED_BYTES,
    max_values: int = MAX_VALUES,
) -> Motion:
    """Read a BVH file from a path, bytes, text or binary file object (gzip detected by content).

    ``max_bytes`` caps the decompressed size of a gzip file and ``max_values`` the frames ×
    channels: callers reading untrusted uploads pass limits that keep memory bounded.
    """
    return parse(_decompress(_load_bytes(source), max_bytes), max_values=max_values)


def _format_number(value: float) -> str:
    return f"{value:.6f}"


def _hierarchy_lines(skeleton: Skeleton) -> tuple[list[str], list[int]]:
    """The HIERARCHY lines and the joints in the order they were written (depth-first)."""
    lines, order = ["HIERARCHY"], []
    ends: dict[int, list[int]] = {int(p): [] for p in skeleton.end_site_parents}
    for k, p in enumerate(skeleton.end_site_parents):
        ends[int(p)].append(k)

    def emit(joint: int, depth: int) -> None:
        tab = "\t" * depth
        order.append(joint)
        keyword = "ROOT" if skeleton.parents[joint] < 0 else "JOINT"
        offset = " ".join(_format_number(v) for v in skeleton.offsets[joint])
        channels = skeleton.channels[joint]
        lines.extend([f"{tab}{keyword} {skeleton.names[joint]}", f"{tab}{{"])
        lines.append(f"{tab}\tOFFSET {offset}")
        lines.append(f"{tab}\tCHANNELS {len(channels)} {' '.join(channels)}".rstrip())
        for child in skeleton.children(joint):
            emit(child, depth + 1)
        for k in ends.get(joint, []):
            site = " ".join(_format_number(v) for v in skeleton.end_site_offsets[k])
            lines.extend(
                [f"{tab}\tEnd Site", f"{tab}\t{{", f"{tab}\t\tOFFSET {site}", f"{tab}\t}}"]
            )
        lines.append(f"{tab}}}")

    # One recursion level per nesting level: the parser caps nesting at 256, below Python's limit.
    emit(0, 0)
    return lines, order


def _frames_in_file_order(motion: Motion, order: list[int]) -> FloatArray:
    """Frame columns for joints written in ``order``: a skeleton built in code (not read from a
    file) need not list its joints depth-first, and the file's frame lines must follow its text."""
    skeleton = motion.skeleton
    if len(order) != len(skeleton.names):
        raise ValueError("dumps needs one root (joint 0) from which every joint is reached")
    if order == list(range(len(order))):
        return motion.frames
    starts = skeleton.channel_starts
    columns = [int(starts[j]) + k for j in order for k in range(len(skeleton.channels[j]))]
    return motion.frames[:, columns]


def dumps(motion: Motion) -> str:
    """The BVH text of a motion (values with 6 decimals: a round trip keeps them to 5e-7)."""
    out = io.StringIO()
    lines, order = _hierarchy_lines(motion.skeleton)
    out.write("\n".join(lines))
    out.write(f"\nMOTION\nFrames: {motion.n_frames}\nFrame Time: {motion.frame_time:.8f}\n")
    if motion.n_frames:
        np.savetxt(out, _frames_in_file_order(motion, order), fmt="%.6f", delimiter=" ")
    return out.getvalue()


def write(motion: Motion, path: str | os.PathLike[str]) -> None:
    """Write a motion to ``path``; a name ending in ``.gz`` is gzip-compressed."""
    text = dumps(motion).encode("utf-8")
    if str(path).endswith(".gz"):
        text = gzip.compress(text, compresslevel=6)
    Path(path).write_bytes(text)
