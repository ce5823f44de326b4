import os

from django.core.management import call_command
from django.core.management.base import BaseCommand
from django.db import connections
from django.utils.autoreload import DJANGO_AUTORELOAD_ENV


class Command(BaseCommand):
    help = (
        "Apply the migrations, load the demo clinic, then run the development server: `make run`'s "
        "server (python -m workers.local --demo). One process for the three, so the site's code "
        "is imported once (each start-up costs seconds), not once for each."
    )
    # runserver runs them, before it serves.
    requires_system_checks: list[str] = []

    def add_arguments(self, parser):
        parser.add_argument("addrport", help="Address and port to serve on, as runserver's.")
        parser.add_argument(
            "--noreload",
            action="store_false",
            dest="use_reloader",
            help="Do not restart the server when the code changes (runserver's --noreload).",
        )

    def handle(self, *args, **options):
        # With the reloader (DEBUG=1) this command runs again in each server process that the
        # reloader starts: the first run, in the watching process, made the database ready.
        if os.environ.get(DJANGO_AUTORELOAD_ENV) != "true":
            call_command("migrate", interactive=False, verbosity=options["verbosity"])
            call_command("load_demo", verbosity=options["verbosity"])
            connections.close_all()  # the server's threads open their own
        call_command(
            "runserver",
            options["addrport"],
            use_reloader=options["use_reloader"],
            skip_checks=False,
            verbosity=options["verbosity"],
        )
