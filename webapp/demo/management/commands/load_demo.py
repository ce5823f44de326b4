from django.conf import settings
from django.core.management.base import BaseCommand, CommandError

from webapp.demo.clinic import DEMO_ACCOUNTS, load_demo_clinic
from workers.celery import app


class Command(BaseCommand):
    help = (
        "Load the demo clinic (demo therapist, demo patient, three exercises). Idempotent. Its "
        "analyses go to the worker when one takes tasks from a broker (`make run`), else run here."
    )
    # The checks import every view (seconds); the server runs them anyway when it starts.
    requires_system_checks: list[str] = []

    def add_arguments(self, parser):
        parser.add_argument(
            "--allow-production",
            action="store_true",
            help="Load even where DEMO_ALLOWED is off (the demo accounts have published "
            "passwords).",
        )
        parser.add_argument(
            "--wait",
            action="store_true",
            help="Build the models and analyse the recordings in this process before returning, "
            "even where a worker would take them.",
        )

    def handle(self, *args, **options):
        if not settings.DEMO_ALLOWED and not options["allow_production"]:
            raise CommandError(
                "Refusing to create demo accounts (their passwords are published): set "
                "DEMO_ALLOWED=1 on a machine meant for trying the site (`make demo` does)."
            )
        # Eager tasks mean no worker will come: the analyses are then this command's to do.
        analyse_here = options["wait"] or bool(app.conf.task_always_eager)
        clinic = load_demo_clinic(analyse_here=analyse_here)
        self.stdout.write(self.style.SUCCESS(f"Demo clinic ready: {clinic.name}"))
        if not analyse_here:
            self.stdout.write("  its recordings are being analysed by the worker")
        # The accounts are said here, on the machine set up for trying the site, never on its
        # pages (a production clinic's pages would show them too).
        for username, password in DEMO_ACCOUNTS:
            self.stdout.write(f"  sign in as {username} (password {password})")
