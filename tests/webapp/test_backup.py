"""`manage.py backup` then `manage.py restore` into an EMPTY database (a new SQLite file, or a new
PostgreSQL database when the suite runs on PostgreSQL) and an empty media folder, in a separate
process: every row and every file comes back identical."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import tarfile
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from django.core.files.base import ContentFile
from django.core.management import CommandError, call_command
from django.db import connection

from tests.personas import make_exercise, make_recording, make_world
from webapp.patients.models import Patient
from webapp.recordings.models import AnalysisRun
from webapp.recordings.storage_backup import EXCLUDED, media_files

ROOT = Path(__file__).resolve().parents[2]
DUMP_ARGS = ["--all", "--natural-foreign", *[f"--exclude={label}" for label in EXCLUDED]]


@pytest.fixture
def clinic_data(db, settings, tmp_path):
    settings.MEDIA_ROOT = tmp_path / "media"
    world = make_world()
    exercise = make_exercise(world.clinic)
    recording = make_recording(world.patient, exercise)
    run = recording.runs.get()
    run.arrays.save("result.npz", ContentFile(b"arrays of the run"), save=True)
    AnalysisRun.objects.filter(pk=run.pk).update(summary={"score": 71.5, "repetitions": []})
    make_recording(world.other_patient, exercise)
    world.other_patient.delete()  # soft-deleted rows are backed up too
    return world


def rows(dump_json: str) -> list[dict]:
    return sorted(json.loads(dump_json), key=lambda row: (row["model"], str(row.get("pk"))))


def dump_here() -> str:
    out = io.StringIO()
    call_command("dumpdata", *DUMP_ARGS, stdout=out, verbosity=0)
    return out.getvalue()


@contextmanager
def empty_database(tmp_path: Path) -> Iterator[str]:
    """The URL of a database with nothing in it, not even tables, of the suite's vendor."""
    if connection.vendor != "postgresql":
        yield f"sqlite:///{tmp_path / 'restored.sqlite3'}"
        return
    import psycopg

    params = connection.settings_dict
    name = f"restore_{uuid.uuid4().hex[:10]}"
    user, host, port = params["USER"] or "postgres", params["HOST"] or "127.0.0.1", params["PORT"]
    server = f"postgresql://{user}@{host}:{port or 5432}/postgres"
    with psycopg.connect(server, autocommit=True) as admin:
        admin.execute(f'CREATE DATABASE "{name}"')
    try:
        yield f"postgres://{user}@{host}:{port or 5432}/{name}"
    finally:
        with psycopg.connect(server, autocommit=True) as admin:
            admin.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


def manage(*args: str, database_url: str, media: Path) -> str:
    env = {**os.environ, "DATABASE_URL": database_url, "MEDIA_ROOT": str(media)}
    env.pop("REDIS_URL", None)
    done = subprocess.run(
        [sys.executable, "manage.py", *args],
        check=False,
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_backup_restores_into_an_empty_database_identically(clinic_data, settings, tmp_path):
    archive = tmp_path / "backup.tar.gz"
    call_command("backup", str(archive), stdout=io.StringIO())
    original_rows = rows(dump_here())
    original_files = media_files(Path(settings.MEDIA_ROOT))
    assert len(original_files) == 4  # the tutor, two uploads and one arrays file
    restored_media = tmp_path / "restored-media"

    with empty_database(tmp_path) as url:
        said = manage("restore", str(archive), database_url=url, media=restored_media)
        restored_rows = rows(manage("dumpdata", *DUMP_ARGS, database_url=url, media=restored_media))

    assert "row counts and checksums verified" in said
    assert restored_rows == original_rows
    assert {row["model"] for row in restored_rows} >= {
        "patients.patient",
        "recordings.recording",
        "recordings.analysisrun",
        "accounts.user",
    }
    patients = [row for row in restored_rows if row["model"] == "patients.patient"]
    assert sum(row["fields"]["deleted_at"] is not None for row in patients) == 1
    assert media_files(restored_media) == original_files


def test_restore_refuses_a_database_with_data(clinic_data, tmp_path):
    archive = tmp_path / "backup.tar.gz"
    call_command("backup", str(archive), stdout=io.StringIO())
    with pytest.raises(CommandError, match="empty database"):
        call_command("restore", str(archive), stdout=io.StringIO())
    assert Patient.all_objects.count() == 3


def test_restore_refuses_a_tampered_archive(clinic_data, tmp_path):
    archive = tmp_path / "backup.tar.gz"
    call_command("backup", str(archive), stdout=io.StringIO())
    tampered = tmp_path / "tampered.tar.gz"
    with tarfile.open(archive) as source, tarfile.open(tampered, "w:gz") as target:
        for member in source.getmembers():
            content = source.extractfile(member).read()
            if member.name.startswith("media/recordings/"):
                content = content[:-1] + bytes([content[-1] ^ 1])
            target.addfile(member, io.BytesIO(content))
    with pytest.raises(CommandError, match="does not match its checksum"):
        call_command("restore", str(tampered), stdout=io.StringIO())
