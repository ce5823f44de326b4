"""`manage.py send_reminders`: e-mail today's reminders of missed sessions now (beat runs the
same daily; a patient gets at most one a day either way)."""

from __future__ import annotations

from django.core.management.base import BaseCommand

from webapp.patients.reminders import send_reminders


class Command(BaseCommand):
    help = "E-mail a reminder to patients behind their sessions this week (reminders on only)."

    def handle(self, *args, **options) -> None:
        self.stdout.write(f"Sent {send_reminders()} reminders")
