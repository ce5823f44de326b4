"""Reading stored recordings with their checksum verified.

Uploads are stored with the SHA-256 of their bytes (`Recording.checksum`, computed before the file
is written). Every read goes through `read_verified`: a file that changed on disk (bit rot, a
partial restore, someone editing it) or went missing is never analysed or shown as if it were
the upload. The recording is marked damaged with the reason, and the caller gets a
`DamagedRecordingError` error whose message can be shown to users as it is.
"""

from __future__ import annotations

import hashlib
import logging

from django.utils import timezone

from analysis.bvh import AnalysisInputError
from webapp.recordings.models import Recording

log = logging.getLogger(__name__)


class DamagedRecordingError(AnalysisInputError):
    """The stored file of a recording is missing or does not match its checksum."""


def sha256_hex(content: bytes) -> str:
    return hashlib.sha256(content).hexdigest()


def read_verified(recording: Recording) -> bytes:
    """The stored bytes of the recording, after checking them against its checksum.

    Raises DamagedRecordingError (and marks the recording) when the file is missing or differs.
    """
    try:
        with recording.file.open("rb") as handle:
            content = handle.read()
    except FileNotFoundError as error:
        raise mark_damaged(recording, "the stored file is missing") from error
    actual = sha256_hex(content)
    if actual != recording.checksum:
        raise mark_damaged(
            recording,
            f"the stored file's SHA-256 {actual[:12]}… differs from the upload's "
            f"{recording.checksum[:12]}…",
        )
    return content


def mark_damaged(recording: Recording, reason: str) -> DamagedRecordingError:
    """Record the damage on the recording and return the error to raise."""
    log.error("recording %s is damaged: %s", recording.pk, reason)
    now = timezone.now()
    Recording.all_objects.filter(pk=recording.pk).update(damaged_at=now, damage=reason[:300])
    recording.damaged_at, recording.damage = now, reason[:300]
    return DamagedRecordingError(
        f"The stored file of this recording is damaged ({reason}); it cannot be read. "
        "Restore it from a backup or upload the recording again."
    )
