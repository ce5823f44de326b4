from __future__ import annotations

from django import forms

from webapp.exercises.models import Exercise
from webapp.patients.models import Patient, Prescription


class PatientForm(forms.ModelForm):
    class Meta:
        model = Patient
        fields = ["display_name", "date_of_birth", "notes"]
        widgets = {"date_of_birth": forms.DateInput(attrs={"type": "date"})}


class PrescriptionForm(forms.ModelForm):
    class Meta:
        model = Prescription
        fields = [
            "exercise",
            "sessions_per_week",
            "target_repetitions",
            "start_date",
            "end_date",
            "notes",
        ]
        widgets = {
            "start_date": forms.DateInput(attrs={"type": "date"}),
            "end_date": forms.DateInput(attrs={"type": "date"}),
        }

    def __init__(self, *args, clinic, **kwargs):
        super().__init__(*args, **kwargs)
        self.fields["exercise"].queryset = Exercise.objects.filter(
            clinic=clinic, archived_at__isnull=True
        )

    def clean(self):
        cleaned = super().clean()
        start, end = cleaned.get("start_date"), cleaned.get("end_date")
        if start and end and end < start:
            self.add_error("end_date", "The end date is before the start date.")
        return cleaned
