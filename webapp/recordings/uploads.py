"""Accepting an uploaded recording: size, parse, skeleton and duplicate checks, then storage.

`accept_upload` is the one way an upload validated by `UploadForm` (the upload page and
``POST /api/v1/recordings/``) becomes a stored recording. Nothing is stored unless every check
passes, and the recording, its first analysis run and the file are written in one transaction;
the analysis is enqueued only after the commit.
"""

from __future__ import annotations

import gzip
import hashlib
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from django.conf import settings
from django.core.exceptions import ValidationError
from django.core.files.base import ContentFile
from django.core.files.uploadedfile import UploadedFile
from django.db import transaction
from django.utils import timezone

from analysis.bvh import (
    BVHError,
    ImplausibleRecordingError,
    Limits,
    Motion,
    SkeletonMismatchError,
    check_recording,
)
from analysis.bvh.plausibility import distinct_durations
from analysis.kinematics import map_onto
from analysis.pipeline.prepare import min_frames
from analysis.sources import SUFFIXES, read_recording
from analysis.sources.video import SUFFIXES as VIDEO_SUFFIXES
from analysis.sources.video import VideoHeader, probe
from webapp.accounts.models import User
from webapp.exercises.models import Exercise
from webapp.patients.models import Patient
from webapp.recordings import services
from webapp.recordings.models import AnalysisRun, Recording
from webapp.recordings.words import file_problem

MIN_FRAMES = 10
MIN_VIDEO_SECONDS = 1.0
VIDEO_JOINTS = 17  # the skeleton a video's landmarks are solved into (`analysis.sources.ik`)
# BVH and the capture sources `analysis.sources` reads (Kinect .csv, Azure/MediaPipe .json, ...)
ACCEPTED_SUFFIXES = SUFFIXES
BVH_SUFFIXES = (".bvh", ".bvh.gz")
# Caps for untrusted files, far above a clinical recording (a 30-minute UI-PRMD session at 30 fps
# is 3.7 M values, 33 MB of text): they bound one upload's memory (~0.3 GB) and time (~1 s).
MAX_DECOMPRESSED_BYTES = 96 << 20
MAX_FRAME_VALUES = 8_000_000
CHECK_FRAMES = 60  # frames the skeleton check retargets


@dataclass(frozen=True)
class ParsedUpload:
    """``motion``: the recording as read; None for a video, whose frames the worker reads (the
    pose estimator takes about 30 ms a frame: the upload answers at once with ``video``, the
    frame rate, size and count read from its header)."""

    content: bytes
    checksum: str
    motion: Motion | None
    original_name: str
    kind: str = "bvh"  # the capture source (`analysis.sources.RecordingSource.kind`)
    video: VideoHeader | None = None

    @property
    def warnings(self) -> tuple[str, ...]:
        """What the reader bent to open the file, in plain words, for the upload page (another
        source's import notes are already sentences for the uploader)."""
        if self.motion is None:
            return ()
        if self.kind != "bvh":
            return self.motion.warnings
        return tuple(upload_notice(w) for w in self.motion.warnings)

    @property
    def suffix(self) -> str:
        """The stored file's ending: the upload's real one, so the worker reads it the same way."""
        name = self.original_name.lower()
        if self.kind == "bvh" or not name.endswith(ACCEPTED_SUFFIXES):
            return ".bvh.gz" if self.content[:2] == b"\x1f\x8b" else ".bvh"
        return next(s for s in ACCEPTED_SUFFIXES if name.endswith(s))


def upload_notice(warning: str) -> str:
    """A reader warning as a sentence for the person uploading."""
    return f"The file was read although it bends the BVH format ({warning})."


def read_upload(upload: UploadedFile) -> bytes:
    limit = settings.MAX_UPLOAD_BYTES
    if upload.size is not None and upload.size > limit:
        raise ValidationError(
            f"The file is {upload.size / 1e6:.1f} MB; the largest accepted is {limit / 1e6:.0f} MB."
        )
    return upload.read(limit + 1)


def parse_upload(upload: UploadedFile, *, any_source: bool = False) -> ParsedUpload:
    """Check an uploaded file is a usable recording; raise ValidationError saying why not.

    ``any_source``: also the capture files `analysis.sources.read_recording` reads (patients'
    recordings); without it BVH only (an exercise's tutor, which is stored and read as BVH).
    """
    name = upload.name or "recording.bvh"
    if not any_source and not name.lower().endswith(BVH_SUFFIXES):
        raise ValidationError("Upload a BVH motion-capture file (.bvh or .bvh.gz).")
    if not name.lower().endswith(ACCEPTED_SUFFIXES):
        raise ValidationError(
            "Upload a BVH motion-capture file (.bvh or .bvh.gz) or another capture file: Kinect "
            "joint positions (.csv or .txt), Azure Kinect, BlazePose or MediaPipe (.json), Vicon "
            "target text (.txt), .trc, .c3d, or a video (.mp4, .mov, .webm)."
        )
    content = read_upload(upload)
    if len(content) > settings.MAX_UPLOAD_BYTES:
        raise ValidationError("The file is larger than the upload limit.")
    if is_video(name):
        return parse_video(content, name)
    try:
        imported = read_recording(
            name,
            content,
            max_bytes=getattr(settings, "MAX_UPLOAD_DECOMPRESSED_BYTES", MAX_DECOMPRESSED_BYTES),
            max_values=getattr(settings, "MAX_UPLOAD_FRAME_VALUES", MAX_FRAME_VALUES),
        )
    except (BVHError, gzip.BadGzipFile, EOFError, UnicodeDecodeError) as error:
        problem = file_problem(str(error))  # the reader's words made plain ("values", not channels)
        what = "BVH file" if imported_kind(name) == "bvh" else "capture file"
        raise ValidationError(f"This is not a readable {what}: {problem}") from error
    motion = imported.motion
    if motion.frames.shape[0] < MIN_FRAMES:
        raise ValidationError(
            f"The recording has {motion.frames.shape[0]} frames; at least {MIN_FRAMES} are needed."
        )
    check_plausible(motion)
    checksum = hashlib.sha256(content).hexdigest()
    return ParsedUpload(content, checksum, motion, name, imported.report.kind)


def is_video(name: str) -> bool:
    return name.lower().endswith(VIDEO_SUFFIXES)


def parse_video(content: bytes, name: str) -> ParsedUpload:
    """A video is checked by its header only (frame rate, size, length); the worker finds the
    person in its frames, with progress, and refuses it there if nobody is seen."""
    suffix = next(s for s in VIDEO_SUFFIXES if name.lower().endswith(s))
    with tempfile.NamedTemporaryFile(suffix=suffix) as handle:
        handle.write(content)
        handle.flush()
        try:
            header = probe(handle.name)
        except BVHError as error:
            raise ValidationError(str(error)) from error
    needed = max(MIN_FRAMES, min_frames(MIN_VIDEO_SECONDS, 1.0 / header.fps))
    if header.frames < needed:
        # Compared in whole frames and printed with enough decimals to differ: never
        # "lasts 1.0 s; at least 1 s is needed".
        lasts, least = distinct_durations(header.frames / header.fps, needed / header.fps)
        raise ValidationError(
            f"The video lasts {lasts} ({header.frames} frames); at least {least} "
            f"({needed} frames) are needed to hold one repetition."
        )
    checksum = hashlib.sha256(content).hexdigest()
    return ParsedUpload(content, checksum, None, name, "video", header)


def stored_motion(name: str, content: bytes) -> Motion | None:
    """A stored recording read back for a skeleton check; None for a video (its skeleton is the
    one every video gets, which maps onto any exercise's; reading its frames takes the worker
    a while)."""
    if is_video(name):
        return None
    return read_recording(name, content).motion


def imported_kind(name: str) -> str:
    """The kind a file name announces: "bvh" or "other" (for the words of a reading error)."""
    return "bvh" if name.lower().endswith(BVH_SUFFIXES) else "other"


def check_plausible(motion: Motion, exercise: Exercise | None = None) -> None:
    """The one plausibility check every analysis runs (`analysis.bvh.check_recording`: frame
    time, length, values, memory), with this site's limits; with the exercise, its model's frame
    rate and joints give the memory estimate."""
    fps, joints = None, None
    if exercise is not None and exercise.tutor_ready():  # a reference video: the worker checks
        tutor = exercise.tutor_motion()
        fps, joints = tutor.fps, len(tutor.skeleton.names)
    try:
        check_recording(motion, fps, joints, Limits.from_settings(settings))
    except ImplausibleRecordingError as error:
        raise ValidationError(str(error)) from error


def check_skeleton(motion: Motion | None, exercise: Exercise) -> None:
    """The recording must map onto the exercise tutor's skeleton: the same rig, or another rig
    whose body parts are recognised (`analysis.kinematics.map_onto`, as the analysis itself does;
    a few frames suffice to check, the analysis maps them all). None: a video, whose skeleton
    the worker makes, always of the body parts every rig's are mapped from."""
    if motion is None:
        return
    check_plausible(motion, exercise)
    if not exercise.tutor_ready():  # a reference video still being read: the worker maps it
        return
    tutor = exercise.tutor_motion()
    try:
        map_onto(motion.with_frames(motion.frames[:CHECK_FRAMES]), tutor.skeleton)
    except SkeletonMismatchError as error:
        raise ValidationError(str(error)) from error


def check_not_duplicate(patient: Patient, checksum: str) -> None:
    """Refuse a file this patient already has, unless that upload still waits for its exercise
    (it is then brought up to date by `store_recording`, not stored twice)."""
    earlier = pending_excluded(Recording.objects.filter(patient=patient, checksum=checksum)).first()
    if earlier is not None:
        when = timezone.localtime(earlier.uploaded_at).strftime("%d %b %Y %H:%M")
        raise ValidationError(f"This file was already uploaded for this patient on {when}.")


def recording_size(parsed: ParsedUpload) -> tuple[int, float]:
    """Frames and frames per second, from the motion or, for a video, its header."""
    if parsed.motion is None:
        assert parsed.video is not None  # parse_video gives every video its header
        return parsed.video.frames, parsed.video.fps
    return parsed.motion.frames.shape[0], 1.0 / parsed.motion.frame_time


def pending_excluded(recordings):
    return recordings.exclude(exercise__isnull=True, runs__isnull=True)


def pending_upload(patient: Patient, checksum: str) -> Recording | None:
    """An earlier upload of the same file that never got an exercise (nor an analysis)."""
    return (
        Recording.objects.filter(
            patient=patient, checksum=checksum, exercise__isnull=True, runs__isnull=True
        )
        .order_by("-uploaded_at")
        .first()
    )


def accept_upload(
    parsed: ParsedUpload | None, data: Mapping[str, Any], user: User
) -> tuple[Recording, AnalysisRun | None]:
    """Store an upload `UploadForm` accepted (its ``parsed`` file and ``cleaned_data``) and start
    its analysis, or, without an exercise, a worker's recognition of the exercise."""
    if parsed is None:  # the form keeps no file once it refused it
        raise ValueError("accept_upload takes the parsed file of a valid upload form")
    return store_recording(
        parsed, patient=data["patient"], exercise=data.get("exercise"), user=user,
        pain_score=data.get("pain_score"), note=data.get("note") or "", effort=data.get("effort"),
    )  # fmt: skip


def store_recording(
    parsed: ParsedUpload,
    *,
    patient: Patient,
    exercise: Exercise | None,
    user: User,
    pain_score: int | None = None,
    note: str = "",
    effort: int | None = None,
) -> tuple[Recording, AnalysisRun | None]:
    """Store the recording, its file and its first run in one transaction; without an exercise,
    a worker is asked to recognise it instead (`services.start_recognition`, after the commit).

    The file is written before the row commits; if the transaction fails it is deleted again, so a
    failed upload leaves no orphan file behind. The same file again while its first upload
    still waits for its exercise updates that upload instead (`reuse_pending`).
    """
    pending = pending_upload(patient, parsed.checksum)
    if pending is not None:
        return reuse_pending(
            pending, exercise=exercise, user=user, pain_score=pain_score, note=note, effort=effort
        )
    recording = new_recording(parsed, patient=patient, exercise=exercise, user=user)
    recording.pain_score, recording.note, recording.effort = pain_score, note, effort
    suffix = parsed.suffix
    try:
        with transaction.atomic():
            recording.file.save(f"{recording.pk}{suffix}", ContentFile(parsed.content), save=False)
            recording.save()
            Patient.objects.filter(pk=patient.pk).update(last_activity_at=timezone.now())
            run = start_first_step(recording)
    except Exception:
        if recording.file.name:
            recording.file.storage.delete(recording.file.name)
        raise
    return recording, run


def start_first_step(recording: Recording) -> AnalysisRun | None:
    """Its analysis when the exercise is named, else the worker's recognition of the exercise."""
    if recording.exercise is not None:
        return services.start_analysis(recording)
    services.start_recognition(recording)
    return None


def reuse_pending(
    recording: Recording, *, exercise, user, pain_score, note, effort=None
) -> tuple[Recording, AnalysisRun | None]:
    """The uploader's new answers on the waiting upload (its file is the same bytes), and its
    analysis started when an exercise is now named (else its recognition, unless under way)."""
    recording.uploaded_by, recording.uploaded_at = user, timezone.now()
    recording.pain_score, recording.note = pain_score, note
    fields = ["uploaded_by", "uploaded_at", "pain_score", "note"]
    if effort is not None:  # asked of patients only: a staff upload keeps the earlier answer
        recording.effort = effort
        fields.append("effort")
    with transaction.atomic():
        recording.save(update_fields=fields)
        Patient.objects.filter(pk=recording.patient_id).update(last_activity_at=timezone.now())
        if exercise is None:
            services.start_recognition(recording)
            return recording, None
        run = services.confirm_exercise(recording, exercise)
    return recording, run


def new_recording(parsed: ParsedUpload, *, patient, exercise, user) -> Recording:
    frames, fps = recording_size(parsed)
    return Recording(
        clinic=patient.clinic,
        patient=patient,
        exercise=exercise,
        checksum=parsed.checksum,
        original_name=parsed.original_name[:255],
        size_bytes=len(parsed.content),
        n_frames=frames,
        n_joints=len(parsed.motion.skeleton.names) if parsed.motion is not None else VIDEO_JOINTS,
        fps=fps,
        duration_s=frames / fps,
        uploaded_by=user,
    )
