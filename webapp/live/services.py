"""The live app's door to the rest: sessions, the exercise model, the upload service."""

from __future__ import annotations

import datetime
import gzip
import hashlib
from collections.abc import Iterable
from typing import Any

from django.core.exceptions import ValidationError
from django.core.files.uploadedfile import SimpleUploadedFile
from django.db import transaction
from django.db.models import Q, QuerySet
from django.utils import timezone

from analysis.bvh import Motion, read
from analysis.live import LiveOptions, rehearse
from analysis.pipeline import FittedModel
from webapp.accounts.models import User
from webapp.accounts.permissions import clinic_scoped
from webapp.exercises.models import Exercise
from webapp.live.models import LiveSession, LiveStatus
from webapp.patients.models import Patient, Prescription
from webapp.recordings.models import Recording
from webapp.recordings.pace import usual_pace
from webapp.recordings.storage import read_verified
from webapp.recordings.uploads import MIN_FRAMES, ParsedUpload, parse_upload, store_recording
from workers.exercise_models import NoUsableModelError, load_active


def visible_sessions(user: User) -> QuerySet[LiveSession]:
    """Live sessions of the user's clinic (a patient: only their own)."""
    return clinic_scoped(LiveSession.objects.all(), user, own="patient__user")


def session_for(user: User, pk: Any) -> LiveSession | None:
    try:
        return visible_sessions(user).select_related("exercise", "patient").get(pk=pk)
    except (LiveSession.DoesNotExist, ValueError):
        return None


def create_session(
    *, patient: Patient, exercise: Exercise, user: User, replay_of: Recording | None = None
) -> LiveSession:
    return LiveSession.objects.create(
        clinic=patient.clinic, patient=patient, exercise=exercise, created_by=user,
        replay_of=replay_of,
    )  # fmt: skip


# Loaded models are cached by `workers.exercise_models` (one cache per process); this only
# remembers which of them this process has already rehearsed.
_REHEARSED: set[Any] = set()


class ModelNotReadyError(ValueError):
    """A live session cannot follow the exercise: it has no model this server can use. The
    message is for the therapist: the consumer answers the session's start with it (an
    ``error`` event), which the capture client prints as its reason for stopping."""


NOT_BUILT = (
    "This exercise's model is not ready, so a live session cannot follow it yet. Build the model "
    "on the exercise's page (Build model), wait until it is ready, then start the session again."
)
OUT_OF_DATE = (
    "This exercise's model was made by an earlier version of the software and must be built "
    "again: use Build model on the exercise's page, then start the session again."
)


def exercise_model(exercise: Exercise) -> FittedModel:
    """The exercise's active model, loaded (never built: fitting takes seconds to minutes, and
    this runs for a server answering live frames). ModelNotReadyError, with the therapist's reason,
    when the exercise has none usable; the live start form does not offer such exercises."""
    try:
        row, model = load_active(exercise)
    except NoUsableModelError as missing:
        raise ModelNotReadyError(OUT_OF_DATE if missing.stale else NOT_BUILT) from missing
    if row.pk not in _REHEARSED:
        rehearse(model)  # here, in a worker thread, not while the event loop's frames wait
        _REHEARSED.add(row.pk)
    return model


def session_options(live: LiveSession) -> LiveOptions:
    """The live judgement's options: the patient's usual pace as the worker's analysis of the
    saved session will read it (their latest session before this one; for a replay, before the
    replayed recording), so the words said live are the words its page says later."""
    replayed = live.replay_of
    before = replayed.uploaded_at if replayed is not None else live.created_at
    return LiveOptions(own_pace=usual_pace(live.patient_id, live.exercise_id, before))


# A session whose capture system sent nothing for this long has stopped without saying so (a
# dropped network, a closed laptop): it leaves the list of sessions under way.
STALE_AFTER = datetime.timedelta(minutes=2)
UNDER_WAY_LIMIT = 20


class SessionEndedError(ValueError):
    """Frames for a session that has ended: it is not re-opened (a second recording would be
    stored under the first one's name); a new session is started instead."""


ENDED = "This session has ended and its recording is saved; start a new session to go on."


def refuse_if_ended(session_id: Any) -> None:
    if LiveSession.objects.filter(pk=session_id, status=LiveStatus.ENDED).exists():
        raise SessionEndedError(ENDED)


def mark_live(live: LiveSession) -> None:
    LiveSession.objects.filter(pk=live.pk, status=LiveStatus.OPEN).update(
        status=LiveStatus.LIVE, last_frame_at=timezone.now()
    )


def record_activity(session_id: Any, repetitions: int | None = None) -> None:
    """Frames arrived for the session (and, when given, its repetitions so far); an ended
    session is left as it is."""
    fields: dict[str, Any] = {"status": LiveStatus.LIVE, "last_frame_at": timezone.now()}
    if repetitions is not None:
        fields["repetitions"] = repetitions
    LiveSession.objects.filter(pk=session_id).exclude(status=LiveStatus.ENDED).update(**fields)


def under_way(user: User, now: datetime.datetime | None = None) -> list[LiveSession]:
    """The user's clinic's sessions of patients exercising now, newest first: not ended, not a
    replay of a stored recording, and a frame (or, before the first, the start) within
    `STALE_AFTER`."""
    cutoff = (now or timezone.now()) - STALE_AFTER
    recent = Q(last_frame_at__gte=cutoff) | Q(last_frame_at__isnull=True, created_at__gte=cutoff)
    sessions = (
        visible_sessions(user)
        .filter(recent, status__in=(LiveStatus.OPEN, LiveStatus.LIVE), replay_of__isnull=True)
        .select_related("patient", "exercise")
        .order_by("-created_at")
    )
    return list(sessions[:UNDER_WAY_LIMIT])


def startable_exercises(patient: Patient) -> list[Exercise]:
    """The exercises a live session can follow for the patient (`startable_of`)."""
    return startable_of(patient.prescriptions.select_related("exercise"))


def startable_of(
    prescriptions: Iterable[Prescription], today: datetime.date | None = None
) -> list[Exercise]:
    """Of these prescriptions (their exercises read with them), the exercises a live session can
    follow: prescribed now, not archived, with a model built (every frame is aligned with it).
    The patient page passes the prescriptions it has read, so offering costs no query."""
    today = today or timezone.localdate()
    chosen = {
        p.exercise.pk: p.exercise
        for p in prescriptions
        if p.start_date <= today
        and (p.end_date is None or p.end_date >= today)
        and p.exercise.followable_live
    }
    return sorted(chosen.values(), key=lambda exercise: exercise.name)


def store_frames(live: LiveSession, bvh_text: str | None, user: User | None) -> Recording | None:
    """The streamed frames as a Recording through the upload service (so the normal pipeline
    analyses it); None for a replay or too few frames."""
    if live.replay_of_id is not None:
        return live.replay_of
    if bvh_text is None:
        return None
    content = gzip.compress(bvh_text.encode(), mtime=0)
    motion = read(content)
    if motion.n_frames < MIN_FRAMES:
        return None
    name = f"live-{timezone.localtime(live.created_at):%Y%m%d-%H%M%S}.bvh.gz"
    parsed = ParsedUpload(content, hashlib.sha256(content).hexdigest(), motion, name)
    recording, _ = store_recording(
        parsed, patient=live.patient, exercise=live.exercise, user=user or live.created_by,
        note="Recorded in a live session.",
    )  # fmt: skip
    return recording


def store_landmarks(
    live: LiveSession, content: bytes, frames: int, user: User | None
) -> Recording | None:
    """A camera session's landmarks as a Recording: a MediaPipe landmark file, read and analysed
    like an uploaded one; None for too few frames (nobody was in view long enough)."""
    if frames < MIN_FRAMES:
        return None
    name = f"camera-{timezone.localtime(live.created_at):%Y%m%d-%H%M%S}.json"
    try:
        parsed = parse_upload(SimpleUploadedFile(name, content), any_source=True)
    except ValidationError:
        return None  # the landmarks never formed a body the reader accepts
    recording, _ = store_recording(
        parsed, patient=live.patient, exercise=live.exercise, user=user or live.created_by,
        note="Recorded live with the camera.",
    )  # fmt: skip
    return recording


def finish(live: LiveSession, summary: dict[str, Any], recording: Recording | None) -> None:
    with transaction.atomic():
        LiveSession.objects.filter(pk=live.pk).update(
            status=LiveStatus.ENDED, ended_at=timezone.now(), summary=summary,
            recording=recording, repetitions=int(summary.get("repetitions") or 0),
        )  # fmt: skip


def replay_motion(live: LiveSession) -> Motion:
    """The stored recording a replay session streams."""
    assert live.replay_of is not None
    return read(read_verified(live.replay_of))
