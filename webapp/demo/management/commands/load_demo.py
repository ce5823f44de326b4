from django.conf import settings
from django.core.management.base import BaseCommand, CommandError

from webapp.demo.clinic import DEMO_ACCOUNTS, load_demo_clinic


class Command(BaseCommand):
    help = "Load the demo clinic (demo therapist, demo patient, three exercises). Idempotent."

    def add_arguments(self, parser):
        parser.add_argument(
            "--allow-production",
            action="store_true",
            help="Load even where DEMO_ALLOWED is off (the demo accounts have published "
            "passwords).",
        )

    def handle(self, *args, **options):
        if not settings.DEMO_ALLOWED and not options["allow_production"]:
            raise CommandError(
                "Refusing to create demo accounts (their passwords are published): set "
                "DEMO_ALLOWED=1 on a machine meant for trying the site (`make demo` does)."
            )
        clinic = load_demo_clinic()
        self.stdout.write(self.style.SUCCESS(f"Demo clinic ready: {clinic.name}"))
        # The accounts are said here, on the machine set up for trying the site, never on its
        # pages (a production clinic's pages would show them too).
        for username, password in DEMO_ACCOUNTS:
            self.stdout.write(f"  sign in as {username} (password {password})")
