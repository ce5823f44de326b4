"""Seeded generator of hostile recordings for `analyse` (issue 25): each case is a file a person
or a broken exporter could upload, built from the repository's test data by one mutation family.

Families (``FAMILIES``, drawn with the weights of ``WEIGHTS``): absurd or malformed frame times;
frame counts that do not match the frame lines (zero, a few, huge, negative, words); skeletons
nested 1 to 1,000 deep; NaN, infinite, huge and malformed values; CHANNELS lines that do not match
the frame lines; files cut short or salted with binary bytes (and damaged gzip); joints of another
rig or renamed; broken structure (braces, a second ROOT, no MOTION). A few cases stay plausible on
purpose (a frame time of 0.05 s, values of 1e5) so that the whole pipeline runs on odd data too.

`hostile_cases(seed, count)` yields ``(family, bytes)``; the same seed gives the same files.
"""

from __future__ import annotations

import gzip
import random
import re
from collections.abc import Callable, Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASE_FILES = (
    "data/ui-prmd/reps/m07_s01_e01.bvh.gz",  # the model's exercise
    "data/ui-prmd/reps/m01_s01_e01.bvh.gz",  # another exercise
    "data/ui-prmd/reps/m07_s01_e02_inc.bvh.gz",  # the model's exercise, done poorly
)
OTHER_RIG = "data/rigs/AnimatedDrawings_cmu1_jumping_jacks.bvh"
_FRAME_TIME = re.compile(rb"Frame Time:[^\n]*")
_FRAMES = re.compile(rb"Frames:[^\n]*")
_CHANNELS = re.compile(rb"CHANNELS[^\n]*")

BAD_FRAME_TIMES = [
    "1000", "100", "10", "1", "0.5", "0.2", "0.11", "0.0009", "1e-4", "1e-9", "0", "-0.0333",
    "-1", "nan", "inf", "-inf", "1e308", "1e-320", "abc", "", "0x10", "1/30", "0,0333", "3e3",
]  # fmt: skip
PLAUSIBLE_FRAME_TIMES = ["0.1", "0.001", "0.05", "0.0083333"]
BAD_COUNTS = [
    "0", "1", "2", "3", "-1", "", "ten", "1e3", "99999999999", "5000001", "4294967296", "+5",
    "1.5", "٣",
]  # fmt: skip
BAD_VALUES = [
    "nan", "NaN", "inf", "-inf", "1e300", "-1e300", "1e20", "3.4e38", "1e7", "-1e7", "1e999",
    "--1", "0x1F", "1e", ".", "١٢", "1_000", "1.2.3", "+", "e5", "\x00",
]  # fmt: skip
PLAUSIBLE_VALUES = ["0", "1e5", "-99999", "1e-300", "720"]
HUMAN_NAMES = [
    "Hips", "Spine", "Neck", "Head", "LeftArm", "LeftForeArm", "LeftHand", "RightUpLeg",
    "RightLeg", "RightFoot", "LeftUpLeg", "LeftLeg", "LeftFoot",
]  # fmt: skip


def base_texts() -> list[bytes]:
    """The uncompressed test recordings every mutation starts from."""
    texts = [gzip.decompress((ROOT / name).read_bytes()) for name in BASE_FILES]
    rig = (ROOT / OTHER_RIG).read_bytes()
    header, _, motion = rig.partition(b"MOTION")
    lines = motion.strip().splitlines()
    short = [lines[0].replace(lines[0].split(b":")[1], b" 40"), lines[1], *lines[2:42]]
    texts.append(header + b"MOTION\n" + b"\n".join(short) + b"\n")
    return texts


def split(text: bytes) -> tuple[bytes, list[bytes]]:
    """(everything up to and including the Frame Time line, the frame lines)."""
    found = _FRAME_TIME.search(text)
    if found is None:
        return text, []
    return text[: found.end()], text[found.end() :].strip().split(b"\n")


def join(head: bytes, rows: list[bytes]) -> bytes:
    return head + b"\n" + b"\n".join(rows) + b"\n"


def frame_time(rng: random.Random, text: bytes) -> bytes:
    pool = PLAUSIBLE_FRAME_TIMES if rng.random() < 0.06 else BAD_FRAME_TIMES
    value = rng.choice(pool) if rng.random() < 0.8 else f"{10 ** rng.uniform(-7, 5):.6g}"
    return _FRAME_TIME.sub(f"Frame Time: {value}".encode(), text, count=1)


def frame_count(rng: random.Random, text: bytes) -> bytes:
    head, rows = split(text)
    if rng.random() < 0.4:
        keep = rng.randint(0, 12)
        head = _FRAMES.sub(f"Frames: {keep}".encode(), head, count=1)
        return join(head, rows[:keep])
    n = len(rows)
    value = rng.choice([*BAD_COUNTS, str(n - 1), str(n + 1), str(2 * n)])
    return join(_FRAMES.sub(f"Frames: {value}".encode(), head, count=1), rows)


def nesting(rng: random.Random, _text: bytes) -> bytes:
    depth = rng.choice([1, 2, 5, 20, 50, 255, 256, 257, 300, 1000])
    names = [rng.choice(HUMAN_NAMES) + (str(i) if rng.random() < 0.5 else "") for i in range(depth)]
    counts = [6 if i == 0 else rng.choice([0, 3, 3, 6]) for i in range(depth)]
    lines = ["HIERARCHY"]
    for i, (name, k) in enumerate(zip(names, counts, strict=True)):
        axes = ["Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"]
        lines += [("ROOT " if i == 0 else "JOINT ") + name, "{", "OFFSET 0 1.5 0"]
        lines.append(f"CHANNELS {k} {' '.join(axes[6 - k :] if k < 6 else axes)}".rstrip())
    lines += ["End Site", "{", "OFFSET 0 1 0", "}"] + ["}"] * depth
    n_frames, n_values = rng.randint(1, 40), sum(counts) + rng.choice([0, 0, 0, 1, -1])
    pose = [f"{rng.uniform(-30, 30):.3f}" for _ in range(max(n_values, 0))]
    rows = [" ".join(pose[k:] + pose[:k]) for k in range(n_frames)]  # a pose turning over
    lines += ["MOTION", f"Frames: {n_frames}", "Frame Time: 0.033333", *rows]
    return "\n".join(lines).encode() + b"\n"


def values(rng: random.Random, text: bytes) -> bytes:
    head, rows = split(text)
    if not rows:
        return text
    choice = rng.random()
    if choice < 0.1:  # every value scaled: a unit mistake or an overflow
        factor = rng.choice([1e4, 1e8, 1e300, -1e3])
        rows = [b" ".join(f"{float(v) * factor:g}".encode() for v in r.split()) for r in rows]
        return join(head, rows)
    if choice < 0.13:  # no movement at all
        return join(head, [rows[0]] * len(rows))
    pool = PLAUSIBLE_VALUES if rng.random() < 0.06 else BAD_VALUES
    rows = list(rows)
    for _ in range(rng.randint(1, 5)):
        i = rng.randrange(len(rows))
        tokens = rows[i].split() or [b"0"]
        tokens[rng.randrange(len(tokens))] = rng.choice(pool).encode()
        rows[i] = b" ".join(tokens)
    return join(head, rows)


def channels(rng: random.Random, text: bytes) -> bytes:
    found = list(_CHANNELS.finditer(text))
    if rng.random() < 0.3 or not found:  # one value more or fewer on some frame lines
        head, rows = split(text)
        step = rng.choice([1, 2, 7])
        rows = [r + b" 0.0" if rng.random() < 0.5 else r.rsplit(b" ", 1)[0] for r in rows[::step]]
        return join(head, rows)
    spot = rng.choice(found)
    words = spot.group().split()
    edits: list[Callable[[list[bytes]], list[bytes]]] = [
        lambda w: [w[0], str(int(w[1]) + rng.choice([-1, 1, 5])).encode(), *w[2:]],
        lambda w: [w[0], rng.choice([b"7", b"-1", b"six", b"0", b"99999"]), *w[2:]],
        lambda w: [*w[:-1], rng.choice([b"Wrotation", b"Xposition", b"xrotation", b"rot"])],
        lambda w: [w[0], str(len(w) - 3).encode(), *w[2:-1]],
        lambda w: [w[0], str(len(w) - 1).encode(), *w[2:], b"Xposition"],
    ]
    words = rng.choice(edits)(words) if len(words) > 2 else [words[0], b"3"]
    return text[: spot.start()] + b" ".join(words) + text[spot.end() :]


def truncate(rng: random.Random, text: bytes) -> bytes:
    return text[: rng.randrange(len(text))]


def binary(rng: random.Random, text: bytes) -> bytes:
    choice = rng.random()
    if choice < 0.25:
        packed = bytearray(gzip.compress(text, compresslevel=1))
        if rng.random() < 0.5:
            return bytes(packed[: rng.randrange(len(packed))])
        packed[rng.randrange(10, len(packed))] ^= 1 << rng.randrange(8)
        return bytes(packed)
    if choice < 0.35:
        return rng.randbytes(rng.randint(0, 4000))
    out = bytearray(text)
    for _ in range(rng.randint(1, 8)):
        junk = rng.choice(
            [b"\x00", b"\xff\xfe", b"\xef\xbb\xbf", rng.randbytes(rng.randint(1, 30))]
        )
        at = rng.randrange(len(out))
        out[at:at] = junk
    return bytes(out)


def rig(rng: random.Random, text: bytes) -> bytes:
    renames = [(b"Left", b"Port"), (b"Right", b"Starboard"), (b"Left", b"Right"), (b"Spine", b"")]
    for _ in range(rng.randint(1, 2)):
        old, new = rng.choice(renames)
        text = text.replace(old, new)
    return text


def structure(rng: random.Random, text: bytes) -> bytes:
    edits: list[Callable[[bytes], bytes]] = [
        lambda t: t.replace(b"}", b"", 1),
        lambda t: t.replace(b"{", b"", 1),
        lambda t: t.replace(b"}", b"}}", 1),
        lambda t: t.replace(b"MOTION", b"MOTON"),
        lambda t: t.replace(b"HIERARCHY", b""),
        lambda t: t.replace(b"ROOT", b"JOINT"),
        lambda t: t.split(b"MOTION")[0] + b"ROOT Again\n{\n}\nMOTION" + t.split(b"MOTION")[-1],
        lambda t: t.split(b"MOTION")[0],
        lambda t: b"",
        lambda t: t.replace(b"OFFSET", b"OFFSET nan", 1),
        lambda t: t.replace(b"\n", b"\r", rng.randint(1, 50)),
        lambda t: t.replace(b"End Site", b"End Site" + str(rng.randint(0, 99)).encode()),
    ]
    return rng.choice(edits)(text)


FAMILIES: dict[str, Callable[[random.Random, bytes], bytes]] = {
    "frame time": frame_time,
    "frame count": frame_count,
    "nesting depth": nesting,
    "values": values,
    "channels": channels,
    "truncated": truncate,
    "binary": binary,
    "other rig": rig,
    "structure": structure,
}
WEIGHTS = {"frame time": 3, "frame count": 2, "nesting depth": 1, "values": 3, "channels": 2,
           "truncated": 2, "binary": 2, "other rig": 0.3, "structure": 1}  # fmt: skip


def family_of(seed: int, index: int) -> tuple[str, random.Random]:
    """The family of case ``index`` and the generator that goes on to build it."""
    rng = random.Random(f"{seed}:{index}")
    names = list(FAMILIES)
    return rng.choices(names, [WEIGHTS[n] for n in names])[0], rng


def hostile_case(seed: int, index: int, bases: list[bytes]) -> tuple[str, bytes]:
    """Case ``index`` of the run seeded ``seed``: (family, file bytes), the same every time (each
    case is built on its own, so a child process can build just its own)."""
    family, rng = family_of(seed, index)
    # the model's own exercise most of the time: its files get furthest into the pipeline
    base = bases[0] if rng.random() < 0.6 else rng.choice(bases)
    return family, FAMILIES[family](rng, base)


def hostile_cases(seed: int, count: int) -> Iterator[tuple[str, bytes]]:
    """``count`` (family, file bytes) pairs, the same for the same seed."""
    bases = base_texts()
    for index in range(count):
        yield hostile_case(seed, index, bases)
