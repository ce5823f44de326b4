from django.conf import settings
from django.core.management.base import BaseCommand, CommandError

from webapp.demo.clinic import load_demo_clinic


class Command(BaseCommand):
    help = "Load the demo clinic (demo therapist, demo patient, three exercises). Idempotent."

    def add_arguments(self, parser):
        parser.add_argument(
            "--allow-production",
            action="store_true",
            help="Load even with DEBUG off (the demo accounts have published passwords).",
        )

    def handle(self, *args, **options):
        if not settings.DEMO_ALLOWED and not options["allow_production"]:
            raise CommandError("Refusing to create demo accounts: DEMO_ALLOWED is off (DEBUG off).")
        clinic = load_demo_clinic()
        self.stdout.write(self.style.SUCCESS(f"Demo clinic ready: {clinic.name}"))
