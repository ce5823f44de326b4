"""`manage.py backup ARCHIVE.tar.gz`: database rows and media files in one archive with a
manifest of checksums (see webapp/recordings/storage_backup.py and the README)."""

from __future__ import annotations

from pathlib import Path

from django.core.management.base import BaseCommand

from webapp.recordings.storage_backup import backup


class Command(BaseCommand):
    help = "Back up the database and the media files into one .tar.gz archive with a manifest."

    def add_arguments(self, parser) -> None:
        parser.add_argument("archive", type=Path, help="the .tar.gz file to write")

    def handle(self, *args, archive: Path, **options) -> None:
        manifest = backup(archive)
        rows = sum(manifest["rows"].values())
        self.stdout.write(
            f"Backed up {rows} rows of {len(manifest['rows'])} models and "
            f"{len(manifest['files'])} files to {archive}"
        )
