"""Live sessions: a patient exercising while the server aligns each frame with the tutor.

Status: OPEN (created) → LIVE (frames arriving) → ENDED (summary stored; the frames became a
Recording, analysed by the normal pipeline). While LIVE, `last_frame_at` and `repetitions` follow
the stream (`webapp.live.services.record_activity`). A replay session streams a stored recording
(``replay_of``) through the same path and stores no new recording.
"""

from __future__ import annotations

import uuid

from django.conf import settings
from django.db import models

from webapp.accounts.models import Clinic


class LiveStatus(models.TextChoices):
    OPEN = "open", "Open"
    LIVE = "live", "Live"
    ENDED = "ended", "Ended"


class LiveSession(models.Model):
    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    clinic = models.ForeignKey(Clinic, on_delete=models.PROTECT, related_name="live_sessions")
    patient = models.ForeignKey(
        "patients.Patient", on_delete=models.CASCADE, related_name="live_sessions"
    )
    exercise = models.ForeignKey(
        "exercises.Exercise", on_delete=models.PROTECT, related_name="live_sessions"
    )
    created_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, related_name="+"
    )
    created_at = models.DateTimeField(auto_now_add=True)
    ended_at = models.DateTimeField(null=True, blank=True)
    status = models.CharField(max_length=8, choices=LiveStatus.choices, default=LiveStatus.OPEN)
    replay_of = models.ForeignKey(
        "recordings.Recording", on_delete=models.CASCADE, null=True, blank=True, related_name="+"
    )
    recording = models.ForeignKey(
        "recordings.Recording",
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="live_sessions",
    )
    summary = models.JSONField(default=dict, blank=True)
    # Kept up to date while frames arrive, so the session shows on the therapist's home page
    # while it runs (not only once it ends); a session with no frame for a while is left off.
    last_frame_at = models.DateTimeField(null=True, blank=True)
    repetitions = models.PositiveIntegerField(default=0)

    class Meta:
        ordering = ["-created_at"]

    def __str__(self) -> str:
        return f"live session {self.pk}"

    @property
    def ws_path(self) -> str:
        return f"/ws/live/{self.pk}/"
