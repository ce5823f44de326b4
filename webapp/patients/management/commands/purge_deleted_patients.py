"""`manage.py purge_deleted_patients`: hard-delete patients soft-deleted longer ago than
PATIENT_RETENTION_DAYS, with their recordings, runs and files (beat also runs it daily)."""

from __future__ import annotations

from django.conf import settings
from django.core.management.base import BaseCommand

from webapp.patients.models import Patient
from workers.housekeeping import purge_deleted_patients


class Command(BaseCommand):
    help = "Delete for good the patients deleted more than PATIENT_RETENTION_DAYS days ago."

    def add_arguments(self, parser) -> None:
        parser.add_argument("--dry-run", action="store_true", help="only say how many")

    def handle(self, *args, dry_run: bool = False, **options) -> None:
        days = settings.PATIENT_RETENTION_DAYS
        if dry_run:
            due = Patient.all_objects.past_retention().count()
            self.stdout.write(f"{due} patients deleted more than {days} days ago would be purged")
            return
        purged = purge_deleted_patients()
        self.stdout.write(f"Purged {purged} patients deleted more than {days} days ago")
