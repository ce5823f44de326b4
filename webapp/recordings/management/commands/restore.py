"""`manage.py restore ARCHIVE.tar.gz`: into an empty database (it runs `migrate` first) and
MEDIA_ROOT, checking every checksum before and after (see the README's backup section)."""

from __future__ import annotations

from pathlib import Path

from django.core.management.base import BaseCommand, CommandError

from webapp.recordings.storage_backup import BackupError, restore


class Command(BaseCommand):
    help = "Restore a backup archive into an empty database and the media folder."

    def add_arguments(self, parser) -> None:
        parser.add_argument("archive", type=Path, help="a .tar.gz written by `manage.py backup`")

    def handle(self, *args, archive: Path, **options) -> None:
        if not archive.is_file():
            raise CommandError(f"No archive at {archive}.")
        try:
            manifest = restore(archive)
        except BackupError as error:
            raise CommandError(str(error)) from error
        rows = sum(manifest["rows"].values())
        self.stdout.write(
            f"Restored {rows} rows and {len(manifest['files'])} files from {archive} "
            f"(backed up {manifest['created_at']}); row counts and checksums verified"
        )
