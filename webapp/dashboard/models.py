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
