"""Recompute the stored attention list of every clinic (beat does it every ten minutes)."""

from __future__ import annotations

from django.core.management.base import BaseCommand

from webapp.dashboard.precompute import refresh_all


class Command(BaseCommand):
    help = __doc__

    def handle(self, *args, **options) -> None:
        count = refresh_all()
        self.stdout.write(f"{count} patient(s) need attention")
