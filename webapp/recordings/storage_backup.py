"""Backup and restore of the whole site: database rows and media files in one archive.

The archive (`.tar.gz`) holds:

- `db.json`: every row (`dumpdata --all --natural-foreign`, so soft-deleted patients are kept and
  content types are matched by name, which makes it loadable into any freshly migrated database,
  SQLite or PostgreSQL);
- `media/...`: every stored file (uploads, result arrays, tutors, exercise models, reports), read
  through Django's default storage: the folder MEDIA_ROOT, or the S3 bucket when S3_BUCKET is set;
- `manifest.json`: format, date, code version, database vendor, the number of rows per model,
  and the SHA-256 and size of `db.json` and of every media file.

`restore` refuses a database that already holds data, checks every checksum before it writes
anything, loads the rows in one transaction, writes the files, then checks the row counts again.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import tarfile
import tempfile
from collections import Counter
from datetime import UTC, datetime
from pathlib import Path, PurePosixPath
from typing import Any

from django.apps import apps
from django.core.files.base import ContentFile
from django.core.files.storage import FileSystemStorage, default_storage
from django.core.management import call_command
from django.db import connection

FORMAT = 1
# Rebuilt by `migrate` in the target, or not worth keeping (sessions expire).
EXCLUDED = ["contenttypes", "auth.permission", "sessions"]


class BackupError(Exception):
    """The archive is unusable or the target is not fit to restore into; the message says why."""


def sha256_file(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def stored_names(storage=default_storage, folder: str = "") -> list[str]:
    """Every file name in the storage (the media folder or the bucket), sorted."""
    try:
        folders, files = storage.listdir(folder)
    except FileNotFoundError:  # no media folder yet
        return []
    names = [f"{folder}/{name}" if folder else name for name in files]
    for sub in folders:
        names += stored_names(storage, f"{folder}/{sub}" if folder else sub)
    return sorted(names)


def stored_bytes(name: str, storage=default_storage) -> bytes:
    with storage.open(name, "rb") as handle:
        return handle.read()


def media_files(storage: Any = default_storage) -> dict[str, dict[str, Any]]:
    """Storage name → {sha256, size} of every stored file (`storage` may be a folder too)."""
    if isinstance(storage, str | Path):
        storage = FileSystemStorage(location=storage)
    found = {}
    for name in stored_names(storage):
        content = stored_bytes(name, storage)
        found[name] = {"sha256": hashlib.sha256(content).hexdigest(), "size": len(content)}
    return found


def row_counts(dump: list[dict[str, Any]]) -> dict[str, int]:
    return dict(sorted(Counter(row["model"] for row in dump).items()))


def dump_database(path: Path) -> list[dict[str, Any]]:
    call_command(
        "dumpdata",
        all=True,
        natural_foreign=True,
        exclude=EXCLUDED,
        output=str(path),
        verbosity=0,
    )
    return json.loads(path.read_text(encoding="utf-8"))


def build_manifest(db_path: Path, dump: list, files: dict[str, dict[str, Any]]) -> dict[str, Any]:
    from analysis import __version__ as code_version

    return {
        "format": FORMAT,
        "created_at": datetime.now(UTC).isoformat(timespec="seconds"),
        "code_version": code_version,
        "database_vendor": connection.vendor,
        "rows": row_counts(dump),
        "database": {"sha256": sha256_file(db_path), "size": db_path.stat().st_size},
        "files": files,
    }


def backup(output: Path) -> dict[str, Any]:
    """Write the archive to `output` (atomically: a half-written archive never has its name)."""
    output.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as work:
        db_path = Path(work) / "db.json"
        dump = dump_database(db_path)
        files = media_files()
        manifest = build_manifest(db_path, dump, files)
        partial = output.with_name(output.name + ".partial")
        with tarfile.open(partial, "w:gz") as archive:
            add_bytes(archive, "manifest.json", json.dumps(manifest, indent=1).encode())
            archive.add(db_path, arcname="db.json")
            for relative in files:
                add_bytes(archive, f"media/{relative}", stored_bytes(relative))
        os.replace(partial, output)
    return manifest


def add_bytes(archive: tarfile.TarFile, name: str, content: bytes) -> None:
    info = tarfile.TarInfo(name)
    info.size = len(content)
    info.mtime = int(datetime.now(UTC).timestamp())
    archive.addfile(info, io.BytesIO(content))


def read_manifest(archive: tarfile.TarFile) -> dict[str, Any]:
    try:
        manifest = json.loads(member_bytes(archive, "manifest.json"))
    except (KeyError, ValueError) as error:
        raise BackupError("This is not a backup archive: manifest.json is missing.") from error
    if manifest.get("format") != FORMAT:
        raise BackupError(f"Unknown backup format {manifest.get('format')!r}.")
    return manifest


def member_bytes(archive: tarfile.TarFile, name: str) -> bytes:
    handle = archive.extractfile(name)
    if handle is None:
        raise KeyError(name)
    return handle.read()


def safe_media_name(relative: str) -> str:
    """The storage name of a file of the archive; refuses names that would escape the storage."""
    pure = PurePosixPath(relative)
    if pure.is_absolute() or ".." in pure.parts:
        raise BackupError(f"Refusing the unsafe file name {relative!r} in the archive.")
    return pure.as_posix()


def verify_archive(archive: tarfile.TarFile, manifest: dict[str, Any]) -> bytes:
    """Check db.json and every listed file against the manifest; return db.json's bytes."""
    database = member_bytes(archive, "db.json")
    if hashlib.sha256(database).hexdigest() != manifest["database"]["sha256"]:
        raise BackupError("db.json does not match its checksum in the manifest.")
    for relative, facts in manifest["files"].items():
        try:
            content = member_bytes(archive, f"media/{relative}")
        except KeyError as error:
            raise BackupError(f"The archive lacks the file {relative}.") from error
        if hashlib.sha256(content).hexdigest() != facts["sha256"]:
            raise BackupError(f"The file {relative} does not match its checksum.")
    return database


def current_counts(labels) -> dict[str, int]:
    return {label: apps.get_model(label)._base_manager.count() for label in labels}


def ensure_empty(labels) -> None:
    filled = {label: n for label, n in current_counts(labels).items() if n}
    if filled:
        shown = ", ".join(f"{label} ({n})" for label, n in sorted(filled.items())[:5])
        raise BackupError(f"Restore only into an empty database; this one has rows in {shown}.")


def write_media(
    archive: tarfile.TarFile, manifest: dict[str, Any], storage=default_storage
) -> None:
    for relative, facts in manifest["files"].items():
        name = safe_media_name(relative)
        if storage.exists(name):
            if hashlib.sha256(stored_bytes(name, storage)).hexdigest() != facts["sha256"]:
                raise BackupError(f"{name} exists with other content; not overwriting it.")
            continue
        saved = storage.save(name, ContentFile(member_bytes(archive, f"media/{relative}")))
        if saved != name:
            raise BackupError(f"{name} could not be written under its own name ({saved}).")


def restore(path: Path) -> dict[str, Any]:
    """Restore an archive into this (empty) database and the storage; returns the manifest."""
    with tarfile.open(path, "r:gz") as archive:
        manifest = read_manifest(archive)
        database = verify_archive(archive, manifest)
        call_command("migrate", interactive=False, verbosity=0)
        ensure_empty(manifest["rows"])
        with tempfile.TemporaryDirectory() as work:
            db_path = Path(work) / "db.json"
            db_path.write_bytes(database)
            call_command("loaddata", str(db_path), verbosity=0)
        write_media(archive, manifest)
    check_restored(manifest)
    return manifest


def check_restored(manifest: dict[str, Any]) -> None:
    counts = current_counts(manifest["rows"])
    wrong = {
        label: (n, counts[label]) for label, n in manifest["rows"].items() if counts[label] != n
    }
    if wrong:
        raise BackupError(f"Row counts differ after the restore (expected, found): {wrong}")
    for relative, facts in manifest["files"].items():
        content = stored_bytes(safe_media_name(relative))
        if hashlib.sha256(content).hexdigest() != facts["sha256"]:
            raise BackupError(f"The restored file {relative} does not match its checksum.")
