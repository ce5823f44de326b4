"""The stored attention list: one small row per patient who needs a therapist's attention.

Computing the list reads a clinic's runs, recordings and prescriptions (`attention.py`); the home
page instead reads a page of these rows. They are kept up to date on write (a run that succeeds
or fails refreshes its patient's row) and by beat (`refresh_attention`, for what changes with
time alone: a failure ageing out, sessions missed). See `webapp.dashboard.precompute`.
"""

from __future__ import annotations

from django.db import models


class PatientAttention(models.Model):
    patient = models.OneToOneField(
        "patients.Patient", on_delete=models.CASCADE, primary_key=True, related_name="+"
    )
    clinic = models.ForeignKey("accounts.Clinic", on_delete=models.CASCADE, related_name="+")
    urgency = models.FloatField()
    # [{"kind": "failed"|"falling"|"adherence", "text": str, "urgency": float,
    #   "recording_id": str | None}, ...], the most urgent first.
    reasons = models.JSONField(default=list)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        indexes = [models.Index(fields=["clinic", "-urgency"], name="attention_clinic_urgency")]

    def __str__(self) -> str:
        return f"attention {self.patient_id}: {len(self.reasons)} reason(s)"


class ProgressPoint(models.Model):
    """One succeeded run's figures on the progress charts, rendered once as JSON text.

    A run's summary is written once, when it succeeds; reading a patient's progression then reads
    these small rows (about 1 kB) instead of extracting from every run's 10–20 kB summary, and the
    JSON endpoints join the texts instead of encoding thousands of points again. What can change
    after the run (exercise name, pain score, upload date) is read from the recording each time.
    Written when the run succeeds (`precompute.refresh_after_run`), in bulk after a bulk load,
    and on a read that finds a run without one (`webapp.patients.progress_store`).
    """

    run = models.OneToOneField(
        "recordings.AnalysisRun",
        on_delete=models.CASCADE,
        primary_key=True,
        related_name="progress_point",
    )
    # `{"score": ..., "repetitions": ..., ...}` as `patient_progress` returns them, and rounded
    # as the API answers them (`webapp.api.numbers.rounded`).
    page = models.TextField()
    api = models.TextField()
    # The body parts the chart legend names (keys of range of motion and γ), a JSON list.
    joints = models.TextField(default="[]")
    # Whether the run has clinical angles or reach areas (the clinical charts' sessions).
    clinical = models.BooleanField(default=False)

    def __str__(self) -> str:
        return f"progress point of run {self.run_id}"
