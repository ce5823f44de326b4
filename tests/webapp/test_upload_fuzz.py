"""Fuzz of the two upload endpoints (the page form and ``POST /api/v1/recordings/``) with damaged
BVH files: every case answers success (page 302, API 201) or 400 with a message, never 500, each
within 2 s, and the process' resident memory grows by less than 1 GiB over the whole run.

Uploads go through the Django test client, so the real middleware, form and parser validate them;
only the enqueue of the analysis is replaced (the worker is not under test). Kinds of damage: the
parser fuzz's mutations of a UI-PRMD recording, damaged or nested gzip, huge declared frame
counts, deep nesting, enormous channel counts, gzip bombs, binary junk and wrong text encodings.
``FUZZ_UPLOAD_EXAMPLES`` (default 3000) is the total, shared by the kinds; `make fuzz` raises it.
"""

from __future__ import annotations

import contextlib
import gc
import gzip
import math
import os
import random
import resource
import time
import tracemalloc
import zlib
from collections import Counter
from dataclasses import dataclass, field
from functools import cache

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.utils.html import escape
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rest_framework.test import APIClient

from analysis.bvh import dumps, read
from tests.analysis.test_bvh_fuzz import HUGE, JUNK, MUTATORS
from tests.personas import fixture_bytes, make_exercise
from webapp.recordings.models import Recording

FUZZ_UPLOAD_EXAMPLES = int(os.environ.get("FUZZ_UPLOAD_EXAMPLES", "1600"))
# Shares of the total: a bomb case costs ~100× a small one, and has few distinct shapes.
WEIGHTS = {
    "mutated": 4,
    "gzip": 2,
    "huge_frames": 2,
    "deep_nesting": 2,
    "many_channels": 2,
    "junk": 2,
    "encoding": 1,
    "gzip_bomb": 0.5,
}
KINDS = tuple(WEIGHTS)


def examples(kind: str) -> int:
    return math.ceil(FUZZ_UPLOAD_EXAMPLES * WEIGHTS[kind] / sum(WEIGHTS.values()))


TIME_LIMIT_S = 2.0
MEMORY_LIMIT_BYTES = 1 << 30
SOURCE = "reps/m01_s01_e02.bvh.gz"  # the exercise's tutor is m01_s01_e01: same rig
NAMES = ["take.bvh", "take.bvh.gz", "TAKE.BVH", "take.bvh.GZ", "a/b/../take.bvh", "täke.bvh"]
ODD_NAMES = ["take.txt", "take", ".bvh", "take.bvh.zip", "x" * 300 + ".bvh", "take.bvh\x00.exe"]
PAIN = [None] * 16 + ["0", "10", "11", "abc"]  # mostly absent: a bad one stops before the file


@cache
def base_text() -> bytes:
    """A short UI-PRMD recording (20 frames) of the exercise's rig: the valid starting point."""
    motion = read(fixture_bytes(SOURCE))
    return dumps(motion.with_frames(motion.frames[:20])).encode()


def frame_lines(n_frames: int, n_values: int, value: bytes = b"0") -> bytes:
    return (b" ".join([value] * n_values) + b"\n") * n_frames


def chain(depth: int, channels: int = 3, closing: int | None = None) -> bytes:
    """A skeleton nested ``depth`` levels deep (``closing`` braces, default balanced)."""
    names = " ".join(["Xrotation", "Yrotation", "Zrotation", "Xposition"][:channels])
    head = b"HIERARCHY\n"
    for level in range(depth):
        keyword = "ROOT" if level == 0 else "JOINT"
        head += f"{keyword} J{level}\n{{\nOFFSET 0 1 0\nCHANNELS {channels} {names}\n".encode()
    head += b"End Site\n{\nOFFSET 0 1 0\n}\n" + b"}\n" * (depth if closing is None else closing)
    return head


def with_frames(head: bytes, n_frames: int, n_values: int, declared: int | None = None) -> bytes:
    declared = n_frames if declared is None else declared
    motion = f"MOTION\nFrames: {declared}\nFrame Time: 0.033333\n".encode()
    return head + motion + frame_lines(n_frames, n_values)


def gzip_stream(parts, repeat: int) -> bytes:
    """Gzip of ``parts`` followed by ``repeat`` copies of the last one, without building it."""
    packer = zlib.compressobj(6, zlib.DEFLATED, 31)
    chunks = [packer.compress(part) for part in parts[:-1]]
    chunks += [packer.compress(parts[-1]) for _ in range(repeat)]
    return b"".join([*chunks, packer.flush()])


@cache
def bombs() -> dict[str, bytes]:
    """Small gzip files that decompress to far more: past the upload caps, or valid but large.

    The upload caps (webapp/recordings/uploads.py) are 96 MiB decompressed and 8 M frame values.
    """
    mib_zeros = bytes(1 << 20)
    rig_rows = frame_lines(1 << 12, 69)  # 4096 frames of the rig's 69 channels, ~0.6 MB
    rig_head = base_text()[: base_text().index(b"MOTION")]
    small_rows, wide_rows = frame_lines(4096, 3), frame_lines(4096, 6)
    return {
        # 128 MiB of zeros (130 kB compressed): above the byte cap.
        "zeros_128MiB": gzip_stream([mib_zeros], 128),
        # A readable BVH of the exercise's rig whose frames decompress to ~110 MB: above the cap.
        "rig_frames_110MB": gzip_stream(
            [rig_head, b"MOTION\nFrames: 800000\nFrame Time: 0.01\n", rig_rows], 195
        ),
        # 12.6 MB, within the byte cap, but declaring 12 M values: above the value cap.
        "values_12M": gzip_stream(
            [chain(2, 3), b"MOTION\nFrames: 2000000\nFrame Time: 0.01\n", wide_rows], 257
        ),
        # The exercise's rig, 98 304 frames (6.8 M values, 13.6 MB; 16 minutes at 100 fps):
        # within the caps, so accepted; without an exercise it is recognised (the slowest path).
        "rig_frames_100k": gzip_stream(
            [rig_head, b"MOTION\nFrames: 98304\nFrame Time: 0.01\n", rig_rows], 24
        ),
        # A 3-channel recording of 1 M frames (3 M values, 6 MB): within the reader's caps, wrong
        # rig, and longer than the plausibility check allows.
        "frames_1M": gzip_stream(
            [chain(1, 3), b"MOTION\nFrames: 1048576\nFrame Time: 0.01\n", small_rows], 256
        ),
        # Gzip inside gzip: the inner layer is not BVH text.
        "nested": gzip.compress(gzip.compress(base_text())),
    }


def pick(draw, options):
    return draw(st.sampled_from(options))


def mutated(draw, rnd) -> bytes:
    return MUTATORS[pick(draw, sorted(MUTATORS))](base_text(), draw, rnd)


def gzipped(draw, rnd) -> bytes:
    inner = mutated(draw, rnd) if draw(st.booleans()) else base_text()
    packed = gzip.compress(inner, compresslevel=1)
    damage = pick(draw, ["none", "truncate", "flip", "members", "trailing"])
    if damage == "truncate":
        return packed[: rnd.randint(0, len(packed))]
    if damage == "flip":
        return MUTATORS["flip"](packed, draw, rnd)
    if damage == "members":
        return packed + gzip.compress(b"0 0 0\n")
    if damage == "trailing":
        return packed + draw(st.binary(max_size=64))
    return packed


def huge_frames(draw, rnd) -> bytes:
    text = base_text()
    count = draw(
        st.sampled_from([b"0", b"9", b"21", b"5000000", b"5000001", b"-1", b"1e9", *HUGE])
        | st.integers(0, 10**30).map(lambda v: str(v).encode())
    )
    text = text.replace(b"Frames: 20", b"Frames: " + count, 1)
    if draw(st.booleans()):  # extra frame lines beyond those declared (up to ~1.3 MB)
        last = text.rstrip().rsplit(b"\n", 1)[-1] + b"\n"
        text += last * draw(st.integers(1, 2000))
    return text


def deep_nesting(draw, rnd) -> bytes:
    depth = draw(st.integers(1, 40) | st.integers(250, 260) | st.integers(261, 5000))
    closing = depth if draw(st.integers(0, 3)) else draw(st.integers(0, depth + 2))
    channels = draw(st.integers(0, 4))
    return with_frames(chain(depth, channels, closing), draw(st.integers(0, 12)), depth * channels)


def many_channels(draw, rnd) -> bytes:
    choice = pick(draw, ["count", "joints", "wide_frames"])
    if choice == "count":  # a CHANNELS count no file can have
        count = draw(st.sampled_from(HUGE) | st.integers(7, 10**12).map(lambda v: str(v).encode()))
        return base_text().replace(b"CHANNELS 6", b"CHANNELS " + count, 1)
    if choice == "joints":  # many 6-channel joints side by side (over the 1024-joint cap, too)
        n_joints = draw(st.integers(1, 1100))
        joint = b"JOINT J\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition "
        joint += b"Zrotation Xrotation Yrotation\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\n"
        head = chain(1, 3, closing=0) + joint * (n_joints - 1) + b"}\n"
        return with_frames(head, draw(st.integers(0, 12)), 3 + 6 * (n_joints - 1))
    n_values = draw(st.integers(1, 200_000))  # frame lines far wider than the skeleton
    return with_frames(chain(1, 3), 12, n_values)


def gzip_bomb(draw, rnd) -> bytes:
    bomb = bombs()[pick(draw, sorted(bombs()))]
    if draw(st.integers(0, 3)) == 0:  # a damaged tail: the decompressor stops mid-stream
        return bomb[: rnd.randint(len(bomb) // 2, len(bomb))]
    return bomb


def junk(draw, rnd) -> bytes:
    choice = pick(draw, ["binary", "prefix", "nul", "lines"])
    if choice == "binary":
        return draw(st.binary(max_size=4096))
    if choice == "prefix":
        return draw(st.binary(min_size=1, max_size=64)) + base_text()
    if choice == "nul":
        return base_text().replace(b"\n", b"\x00\n", rnd.randint(1, 50))
    lines = [pick(draw, JUNK) for _ in range(draw(st.integers(1, 40)))]
    return b"\n".join(lines)


def encoding(draw, rnd) -> bytes:
    text = base_text().decode()
    choice = pick(draw, ["utf-16", "utf-16-le", "utf-32", "latin-1 name", "bom", "cp1252 name"])
    if choice == "bom":
        return "\ufeff".encode() + base_text()
    if choice.endswith(" name"):
        renamed = text.replace("Hips", "Hüfte", 1).replace("Spine", "Rücken€", 1)
        return renamed.encode(choice.split()[0], errors="replace")
    return text.encode(choice)


BUILDERS = {
    "mutated": mutated,
    "gzip": gzipped,
    "huge_frames": huge_frames,
    "deep_nesting": deep_nesting,
    "many_channels": many_channels,
    "gzip_bomb": gzip_bomb,
    "junk": junk,
    "encoding": encoding,
}


@dataclass
class Tally:
    outcomes: Counter = field(default_factory=Counter)
    slowest_cpu_s: float = 0.0
    slowest_wall_s: float = 0.0
    traced_peak_bytes: int = 0


def messages(body) -> list[str]:
    """Every error message in a JSON error body (DRF lists or Django's get_json_data dicts)."""
    if isinstance(body, str):
        return [body]
    if isinstance(body, dict):
        if "message" in body:
            return messages(body["message"])
        return [m for value in body.values() for m in messages(value)]
    if isinstance(body, list):
        return [m for value in body for m in messages(value)]
    return []


def check_api(response) -> str:
    if response.status_code == 201:
        assert Recording.objects.filter(pk=response.json()["id"]).exists()
        return "201"
    assert response.status_code == 400, (response.status_code, response.content[:300])
    found = messages(response.json())
    assert found and all(m.strip() for m in found), response.content[:300]
    return f"400 {error_key(response.json())}"


def check_page(response) -> str:
    if response.status_code == 302:
        assert "/recordings/" in response["Location"]
        return "302"
    assert response.status_code == 400, (response.status_code, response.content[:300])
    errors = response.context["form"].errors
    assert errors and all(m.strip() for ms in errors.values() for m in ms), errors
    shown = response.content.decode()
    assert any(escape(m) in shown for ms in errors.values() for m in ms)  # the page says why
    return f"400 {next(iter(errors))}"


def error_key(body: dict) -> str:
    return next(iter(body)) if body else "?"


def current_rss_bytes() -> int:
    with open("/proc/self/statm") as handle:
        return int(handle.read().split()[1]) * resource.getpagesize()


def peak_rss_bytes() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux reports KiB


@dataclass(frozen=True)
class Case:
    content: bytes
    name: str = "take.bvh"
    with_exercise: bool = True
    pain: str | None = None
    endpoint: str = "api"


@dataclass(frozen=True)
class Target:
    """The therapist's two signed-in clients and the patient and exercise uploads name."""

    api: APIClient
    page: APIClient
    patient_id: str
    exercise_id: str

    def post(self, case: Case) -> str:
        """Upload, check the answer, and return its outcome ('api 201', 'page 400 file', ...)."""
        data = {"patient": self.patient_id, "file": SimpleUploadedFile(case.name, case.content)}
        data["exercise"] = self.exercise_id if case.with_exercise else ""
        if case.pain is not None:
            data["pain_score"] = case.pain
        if case.endpoint == "api":
            response = self.api.post("/api/v1/recordings/", data, format="multipart")
            return f"api {check_api(response)}"
        response = self.page.post("/recordings/upload/", data, format="multipart")
        return f"page {check_page(response)}"


@pytest.fixture
def target(world, monkeypatch) -> Target:
    # The single enqueue point (services.start_analysis, after commit): the worker is not tested.
    monkeypatch.setattr("workers.tasks.analyse_recording.delay", lambda run_id: None)
    exercise = make_exercise(world.clinic)
    api = APIClient()
    api.force_authenticate(world.therapist)
    page = (
        APIClient()
    )  # a Django test client with DRF's multipart encoder; the page is plain Django
    page.force_login(world.therapist)
    return Target(api, page, str(world.patient.pk), str(exercise.pk))


@pytest.fixture(scope="module")
def warm():
    """Build the bombs and load the compiled parser (and its error paths) before timing."""
    bombs()
    read(base_text())
    for damaged in (base_text()[:-40], base_text().replace(b"0.", b"x.", 1)):
        with contextlib.suppress(ValueError):
            read(damaged)


# Cases measured with tracemalloc (it slows allocation, so not the cheap kinds).
TRACED = ("gzip_bomb", "huge_frames", "many_channels", "deep_nesting")


def timed_case(
    target: Target, case: Case, tally: Tally, traced: bool, collect: bool = False
) -> str:
    if traced:
        tracemalloc.start()
    wall, cpu = time.perf_counter(), time.thread_time()
    try:
        outcome = target.post(case)
    finally:
        cpu, wall = time.thread_time() - cpu, time.perf_counter() - wall
        if traced:
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            tally.traced_peak_bytes = max(tally.traced_peak_bytes, peak)
    if collect:
        # A form is a reference cycle (its bound-field cache), so the parsed recording it holds
        # waits for the cyclic collector; without this, pending garbage of earlier bombs would be
        # counted as this case's memory. (In a server the collector runs on its own schedule.)
        gc.collect()
    tally.outcomes[outcome] += 1
    tally.slowest_cpu_s = max(tally.slowest_cpu_s, cpu)
    tally.slowest_wall_s = max(tally.slowest_wall_s, wall)
    # CPU time: the machine running the suite may be shared; wall time is reported alongside.
    assert cpu < TIME_LIMIT_S, f"{cpu:.2f} s CPU ({wall:.2f} s wall) for {len(case.content)} bytes"
    return outcome


@contextlib.contextmanager
def frozen_heap():
    """Objects alive now (Django, numpy, hypothesis...) skip the collections made between cases:
    each `gc.collect()` then scans only what the cases created, in milliseconds, not a second."""
    gc.collect()
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def frozen_items(mapping: dict):
    with frozen_heap():
        yield from mapping.items()


def draw_case(kind: str, data) -> Case:
    rnd = random.Random(data.draw(st.integers(0, 2**32 - 1)))
    content = BUILDERS[kind](data.draw, rnd)
    odd_name = data.draw(st.integers(0, 9)) == 0
    name = data.draw(st.sampled_from(ODD_NAMES if odd_name else NAMES))
    if content[:2] == b"\x1f\x8b" and not odd_name:
        name = "take.bvh.gz"
    return Case(
        content,
        name,
        with_exercise=data.draw(st.integers(0, 7)) > 0,  # else the system recognises it
        pain=data.draw(st.sampled_from(PAIN)),
        endpoint=data.draw(st.sampled_from(["api", "api", "page"])),  # a page costs 2× more
    )


def report(title: str, tally: Tally, growth: int) -> None:
    print(
        f"\n{title}: {sum(tally.outcomes.values())} cases {dict(sorted(tally.outcomes.items()))} "
        f"slowest {tally.slowest_cpu_s:.3f} s CPU / {tally.slowest_wall_s:.3f} s wall, "
        f"traced peak {tally.traced_peak_bytes / 2**20:.0f} MiB, "
        f"RSS peak growth {growth / 2**20:.0f} MiB"
    )


def warm_endpoints(target: Target) -> None:
    """First requests load templates and lazy imports: not part of any timed case."""
    for endpoint in ("api", "page"):
        target.post(Case(base_text()[:50], endpoint=endpoint))


@pytest.mark.parametrize("kind", KINDS)
def test_damaged_uploads_answer_success_or_400(kind, target, warm):
    warm_endpoints(target)
    tally = Tally()
    rss_before = current_rss_bytes()

    @settings(
        max_examples=examples(kind),
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(st.data())
    def run(data):
        case = draw_case(kind, data)
        timed_case(target, case, tally, kind in TRACED, collect=kind == "gzip_bomb")

    with frozen_heap():
        run()
    growth = max(peak_rss_bytes() - rss_before, 0)
    report(kind, tally, growth)
    assert sum(tally.outcomes.values()) >= examples(kind)
    assert any(k.split()[1] == "400" for k in tally.outcomes), tally.outcomes
    if kind in ("mutated", "gzip"):  # light damage leaves a usable recording: it is stored
        assert any(k.split()[1] in ("201", "302") for k in tally.outcomes), tally.outcomes
    assert growth < MEMORY_LIMIT_BYTES
    assert tally.traced_peak_bytes < MEMORY_LIMIT_BYTES


EXPECTED_BOMB_OUTCOMES = {
    # (bomb, with the exercise) -> outcome; the reason names the cap that stopped it.
    ("zeros_128MiB", True): ("400", "larger than 96 MiB"),
    ("zeros_128MiB", False): ("400", "larger than 96 MiB"),
    ("rig_frames_110MB", True): ("400", "larger than 96 MiB"),
    ("values_12M", True): ("400", "at most 8000000 are accepted"),
    # 2.9 hours of frames: past the site's maxima (issue 25), whatever its rig or exercise
    ("frames_1M", True): ("400", "at most 500,000 can be analysed"),
    ("frames_1M", False): ("400", "at most 500,000 can be analysed"),
    ("rig_frames_100k", True): ("201", ""),
    ("rig_frames_100k", False): ("201", ""),
    ("nested", True): ("400", "not a readable BVH"),
}


def test_every_bomb_is_refused_or_accepted_in_time_and_memory(target, warm):
    """Each bomb, with and without the exercise: the expected answer, under 2 s and 1 GiB."""
    warm_endpoints(target)
    tally = Tally()
    rss_before = current_rss_bytes()
    for (bomb, with_exercise), (status, reason) in frozen_items(EXPECTED_BOMB_OUTCOMES):
        case = Case(bombs()[bomb], "take.bvh.gz", with_exercise=with_exercise)
        outcome = timed_case(target, case, tally, traced=True, collect=True)
        assert outcome.split()[1] == status, (bomb, with_exercise, outcome)
        Recording.objects.all().delete()  # the next case may upload the same file again
        if reason:
            response = target.api.post(  # the same upload again, to read the message
                "/api/v1/recordings/",
                {
                    "patient": target.patient_id,
                    "exercise": target.exercise_id if with_exercise else "",
                    "file": SimpleUploadedFile("take.bvh.gz", case.content),
                },
                format="multipart",
            )
            assert reason in " ".join(messages(response.json())), (bomb, response.json())
    growth = max(peak_rss_bytes() - rss_before, 0)
    report("bombs", tally, growth)
    assert growth < MEMORY_LIMIT_BYTES
    assert tally.traced_peak_bytes < MEMORY_LIMIT_BYTES
