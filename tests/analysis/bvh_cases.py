"""BVH text builders for the tests: random skeletons, edge-case layouts and small fixed files.

A `Case` keeps the skeleton *as generated* (not as parsed) and the frame values exactly as written
(``float`` of every token), so tests can compare the parser and the kinematics against an
independent source of truth. Joints are numbered in file order (depth-first, pre-order).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

Vec3 = tuple[float, float, float]
ROTATIONS = ("Xrotation", "Yrotation", "Zrotation")
POSITIONS = ("Xposition", "Yposition", "Zposition")
TAIT_BRYAN_ORDERS = tuple("".join(p) for p in itertools.permutations("XYZ"))
SIX_BANDAI = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")


@dataclass(frozen=True)
class JointSpec:
    name: str
    parent: int
    offset: Vec3
    channels: tuple[str, ...]


@dataclass(frozen=True)
class Case:
    """A skeleton with frames: ``tokens`` (F, C) as written, ``values`` their float values."""

    joints: tuple[JointSpec, ...]
    end_sites: tuple[tuple[int, Vec3], ...]
    tokens: list[list[str]]
    frame_time: float = 1 / 30
    offset_tokens: dict[int, tuple[str, str, str]] = field(default_factory=dict)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @property
    def parents(self) -> np.ndarray:
        return np.array([j.parent for j in self.joints], dtype=np.int64)

    @property
    def offsets(self) -> np.ndarray:
        return np.array([j.offset for j in self.joints], dtype=np.float64).reshape(-1, 3)

    @property
    def channels(self) -> tuple[tuple[str, ...], ...]:
        return tuple(j.channels for j in self.joints)

    @property
    def n_channels(self) -> int:
        return sum(len(j.channels) for j in self.joints)

    @property
    def values(self) -> np.ndarray:
        rows = [[float(t) for t in row] for row in self.tokens]
        return np.array(rows, dtype=np.float64).reshape(len(self.tokens), self.n_channels)

    def text(self, newline: str = "\n", indent: str = "\t", sep: str = " ") -> str:
        lines = hierarchy_lines(self, indent)
        lines += ["MOTION", f"Frames: {len(self.tokens)}", f"Frame Time: {self.frame_time!r}"]
        lines += [sep.join(row) for row in self.tokens]
        return newline.join(lines) + newline


def _offset_text(case: Case, joint: int) -> str:
    if joint in case.offset_tokens:
        return " ".join(case.offset_tokens[joint])
    return " ".join(repr(v) for v in case.joints[joint].offset)


def _close(
    case: Case, joint: int, depth: int, indent: str, ends: dict[int, list[Vec3]]
) -> list[str]:
    pad = indent * depth
    lines = []
    for site in ends.get(joint, []):
        lines += [f"{pad}{indent}End Site", f"{pad}{indent}{{"]
        lines += [f"{pad}{indent * 2}OFFSET {' '.join(repr(v) for v in site)}", f"{pad}{indent}}}"]
    return [*lines, f"{pad}}}"]


def hierarchy_lines(case: Case, indent: str = "\t") -> list[str]:
    """HIERARCHY lines of a pre-ordered skeleton, written without recursion."""
    ends: dict[int, list[Vec3]] = {}
    for parent, site in case.end_sites:
        ends.setdefault(parent, []).append(site)
    lines, stack = ["HIERARCHY"], []
    for index, joint in enumerate(case.joints):
        while stack and stack[-1] != joint.parent:
            lines += _close(case, stack.pop(), len(stack), indent, ends)
        pad = indent * len(stack)
        keyword = "ROOT" if joint.parent < 0 else "JOINT"
        lines += [f"{pad}{keyword} {joint.name}", f"{pad}{{"]
        lines.append(f"{pad}{indent}OFFSET {_offset_text(case, index)}")
        lines.append(f"{pad}{indent}CHANNELS {len(joint.channels)} {' '.join(joint.channels)}")
        stack.append(index)
    while stack:
        lines += _close(case, stack.pop(), len(stack), indent, ends)
    return lines


# ---------------------------------------------------------------- random skeletons and frames


def random_number_text(rng: np.random.Generator, value: float) -> str:
    """One of several spellings: plain, fixed, exponent (e/E, signed), integer when whole."""
    style = int(rng.integers(0, 6))
    if style == 0:
        return repr(float(value))
    if style == 1:
        return f"{value:.6f}"
    if style == 2:
        return f"{value:.9e}"
    if style == 3:
        return f"{value:+.8E}"
    if style == 4:
        return f"{value * 1e3:.7f}e-3"
    return f"{round(value)}"


def random_channels(rng: np.random.Generator, positions: bool) -> tuple[str, ...]:
    """Rotation axes in any order (3, 2, 1 or 0 of them) with optional (partial) positions."""
    n_rot = int(rng.choice([3, 3, 3, 2, 1, 0] if positions else [3, 3, 3, 2, 1]))
    order = TAIT_BRYAN_ORDERS[int(rng.integers(0, 6))][:n_rot]
    rotation = [f"{axis}rotation" for axis in order]
    if not positions:
        return tuple(rotation)
    n_pos = int(rng.choice([3, 3, 3, 2, 1]))
    position = [POSITIONS[k] for k in rng.permutation(3)[:n_pos]]
    if rng.random() < 0.7:
        return (*position, *rotation)
    return (*rotation, *position)


def random_tree(rng: np.random.Generator, n_joints: int) -> list[int]:
    """Parents of a random tree numbered in pre-order: each joint hangs off the current path."""
    parents, path = [-1], [0]
    for joint in range(1, n_joints):
        keep = int(rng.integers(1, len(path) + 1))
        path = path[:keep]
        parents.append(path[-1])
        path.append(joint)
    return parents


def random_case(
    rng: np.random.Generator, n_joints: int, n_frames: int, position_prob: float = 0.3
) -> Case:
    """Random skeleton: any channel order/count per joint, positions on some non-root joints."""
    parents = random_tree(rng, n_joints)
    joints = []
    for j, parent in enumerate(parents):
        has_pos = parent < 0 or rng.random() < position_prob
        offset = tuple(float(v) for v in np.round(rng.normal(0, 20, 3), 4))
        joints.append(
            JointSpec(f"J{j}_{rng.integers(1000)}", parent, offset, random_channels(rng, has_pos))
        )  # type: ignore[arg-type]
    leaves = [j for j in range(n_joints) if j not in parents]
    ends = tuple((j, tuple(float(v) for v in np.round(rng.normal(0, 5, 3), 3))) for j in leaves)
    tokens = random_tokens(rng, tuple(joints), n_frames)
    return Case(tuple(joints), ends, tokens, frame_time=float(rng.choice([1 / 30, 1 / 120, 0.01])))  # type: ignore[arg-type]


def random_tokens(
    rng: np.random.Generator, joints: Sequence[JointSpec], n_frames: int
) -> list[list[str]]:
    """Smooth-ish random frames: angles within ±180°, positions around the OFFSET."""
    rows = []
    phase = rng.uniform(0, 2 * np.pi, 64)
    for f in range(n_frames):
        row = []
        for j, joint in enumerate(joints):
            for k, channel in enumerate(joint.channels):
                wave = np.sin(0.2 * f + phase[(j * 6 + k) % 64])
                if channel.endswith("rotation"):
                    value = 170.0 * wave + rng.normal(0, 5)
                else:
                    value = joint.offset["XYZ".index(channel[0])] + 30 * wave
                row.append(random_number_text(rng, float(value)))
        rows.append(row)
    return rows


def bandai_like_case(rng: np.random.Generator, n_frames: int) -> Case:
    """Like Bandai-Namco's files: a static root above the real root, 6 channels on every joint
    (positions first, then Z X Y rotations), bones along +x so the rest pose is not upright."""
    spec = [
        ("joint_Root", -1, (0.0, 0.0, 0.0)),
        ("Hips", 0, (4.5925, 91.4895, -427.239)),
        ("Spine", 1, (15.7357, 0.0, 0.0)),
        ("Chest", 2, (8.98455, -0.406207, 0.0)),
        ("Neck", 3, (16.3773, 0.0, 0.0)),
        ("Shoulder_L", 3, (12.9942, -0.242716, 4.98039)),
        ("UpperArm_L", 5, (5.34809, 0.0, 0.0)),
        ("UpperLeg_R", 1, (-2.19248, -6.46944, 0.0)),
        ("LowerLeg_R", 7, (39.0811, 0.0, 0.0)),
    ]
    joints = tuple(JointSpec(n, p, o, SIX_BANDAI) for n, p, o in spec)
    tokens = random_tokens(rng, joints, n_frames)
    for row in tokens:
        row[:6] = ["0.000000", "0.000000", "0.000000", "0.000000", "0.000000", "-0.000000"]
    ends = ((4, (6.45672, 0.0, 0.0)), (6, (24.3286, 0.0, 0.0)), (8, (40.9854, 0.0, 0.0)))
    return Case(joints, ends, tokens, frame_time=0.0333333)


def arm_case(elbow_degrees: Sequence[float]) -> Case:
    """Shoulder (root) → Elbow → Wrist → End Site, all 30 long along -y; the elbow bends about z."""
    rot = ("Zrotation", "Xrotation", "Yrotation")
    joints = (
        JointSpec("Shoulder", -1, (0.0, 0.0, 0.0), (*POSITIONS, *rot)),
        JointSpec("Elbow", 0, (0.0, -30.0, 0.0), rot),
        JointSpec("Wrist", 1, (0.0, -30.0, 0.0), rot),
    )
    tokens = [
        ["1", "2", "3", "0", "0", "0", f"{a}", "0", "0", "0", "0", "0"] for a in elbow_degrees
    ]
    return Case(joints, ((2, (0.0, -10.0, 0.0)),), tokens)


# ---------------------------------------------------------------- fixed texts and edits

# Line numbers matter: malformed cases are edits of this file and assert the reported line.
SMALL = """HIERARCHY
ROOT Hips
{
\tOFFSET 0.0 0.0 0.0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Knee
\t{
\t\tOFFSET 0.0 -40.0 0.0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0.0 -40.0 0.0
\t\t}
\t}
}
MOTION
Frames: 3
Frame Time: 0.0333333
1.0 90.0 2.0 10.0 0.0 0.0 45.0 0.0 0.0
1.5 90.5 2.5 20.0 0.0 0.0 50.0 0.0 0.0
2.0 91.0 3.0 30.0 0.0 0.0 55.0 0.0 0.0
"""
SMALL_LINES = SMALL.splitlines()
SMALL_FIRST_FRAME_LINE = 19


def edit_line(text: str, line: int, new: str | None) -> str:
    """Replace 1-based ``line`` by ``new`` (None deletes it)."""
    lines = text.splitlines()
    lines[line - 1 : line] = [] if new is None else [new]
    return "\n".join(lines) + "\n"


def insert_line(text: str, before: int, new: str) -> str:
    lines = text.splitlines()
    lines.insert(before - 1, new)
    return "\n".join(lines) + "\n"


def deep_chain_text(depth: int) -> str:
    """A chain of ``depth`` nested joints (no indentation, so the text stays small)."""
    head = ["HIERARCHY", "ROOT J0", "{", "OFFSET 0 0 0", "CHANNELS 3 Zrotation Xrotation Yrotation"]
    body = [
        f"JOINT J{k}\n{{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation"
        for k in range(1, depth)
    ]
    tail = ["}"] * depth + ["MOTION", "Frames: 1", "Frame Time: 0.01", " ".join(["0"] * 3 * depth)]
    return "\n".join(head + body + tail) + "\n"


def flat_skeleton_text(n_joints: int, n_frames: int = 1, channels: int = 3) -> str:
    """A root with ``n_joints - 1`` children (a wide, shallow skeleton)."""
    names = " ".join(ROTATIONS[:channels])
    lines = ["HIERARCHY", "ROOT R", "{", "OFFSET 0 0 0", f"CHANNELS {channels} {names}"]
    for k in range(1, n_joints):
        lines += [f"JOINT C{k}", "{", "OFFSET 1 0 0", f"CHANNELS {channels} {names}", "}"]
    lines += ["}", "MOTION", f"Frames: {n_frames}", "Frame Time: 0.01"]
    lines += [" ".join(["0"] * channels * n_joints)] * n_frames
    return "\n".join(lines) + "\n"
