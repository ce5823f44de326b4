from __future__ import annotations

from django import forms

from webapp.exercises.models import Exercise
from webapp.patients.dosage import DAY_NAMES
from webapp.patients.models import DOSAGE_LIMITS, WEEKDAYS, Patient, Prescription

# A date input reads and sends only ISO dates (2027-09-01): a "09/01/2027" value is dropped
# by the browser and the form then sends nothing.
ISO_DATE = "%Y-%m-%d"
DAY_CHOICES = list(zip(WEEKDAYS, DAY_NAMES, strict=True))


class PatientForm(forms.ModelForm):
    class Meta:
        model = Patient
        fields = ["display_name", "date_of_birth", "notes", "send_reminders", "email"]
        widgets = {"date_of_birth": forms.DateInput(attrs={"type": "date"}, format=ISO_DATE)}
        labels = {
            "send_reminders": "E-mail the patient a reminder when they fall behind this week",
            "email": "Patient's e-mail address for reminders",
        }
        help_texts = {
            "send_reminders": "At most one a day. It names the exercises and the sessions left, "
            "nothing else.",
            "email": "Leave empty to use the address of the patient's own account.",
        }


class PrescriptionForm(forms.ModelForm):
    days = forms.MultipleChoiceField(
        choices=DAY_CHOICES,
        required=False,
        widget=forms.CheckboxSelectMultiple,
        label="On these days (optional)",
    )

    class Meta:
        model = Prescription
        fields = [
            "exercise",
            "sessions_per_week",
            "sets",
            "target_repetitions",
            "hold_seconds",
            "days",
            "start_date",
            "end_date",
            "notes",
        ]
        labels = {
            "sessions_per_week": "Sessions per week (1–7)",
            "sets": "Sets per session",
            "target_repetitions": "Repetitions per set",
            "hold_seconds": "Hold each repetition for (seconds)",
            "notes": "Instructions for the patient",
        }
        help_texts = {
            "sessions_per_week": "Leave empty to use the number of days chosen below.",
        }
        widgets = {
            "start_date": forms.DateInput(attrs={"type": "date"}, format=ISO_DATE),
            "end_date": forms.DateInput(attrs={"type": "date"}, format=ISO_DATE),
        }

    def __init__(self, *args, clinic, **kwargs):
        super().__init__(*args, **kwargs)
        self.fields["exercise"].queryset = Exercise.objects.filter(
            clinic=clinic, archived_at__isnull=True
        )
        for name, (low, high) in DOSAGE_LIMITS.items():
            self.fields[name].widget.attrs.update(min=low, max=high)
        if self.instance.pk:
            self.initial["days"] = self.instance.days.split(",") if self.instance.days else []

    def clean(self):
        cleaned = super().clean()
        start, end = cleaned.get("start_date"), cleaned.get("end_date")
        if start and end and end < start:
            self.add_error("end_date", "The end date is before the start date.")
        days = [day for day in (cleaned.get("days") or "").split(",") if day]
        if "sessions_per_week" in cleaned and cleaned["sessions_per_week"] is None and days:
            cleaned["sessions_per_week"] = len(days)
        return cleaned

    def clean_days(self) -> str:
        chosen = set(self.cleaned_data.get("days") or [])
        return ",".join(day for day in WEEKDAYS if day in chosen)
