"""Fill the database with a large clinic for scale measurements (bench/bench_scale.py).

    manage.py fill_large_clinic --patients 10000 --runs 1000000

On PostgreSQL the rows stream through COPY (one per table, in one transaction); other databases
get batched INSERTs, which is enough for the small clinics the query-count tests use. Each
succeeded run gets the progress point a worker stores, and a line every 100,000 rows shows how
far the fill got. Never run
it against a database that holds real patients: it is meant for a throw-away database.
"""

from __future__ import annotations

import datetime
import io
import json
import random
import time
import uuid
from collections.abc import Iterator

from django.core.management.base import BaseCommand, CommandError
from django.db import connection, models, transaction
from django.utils import timezone

from analysis.pipeline.results import AnalysisSummary
from webapp.accounts.models import Clinic, Role, User
from webapp.dashboard.models import ProgressPoint
from webapp.demo import large_clinic as gen
from webapp.exercises.models import Exercise, ExerciseModel, ModelStatus
from webapp.patients.models import Patient, PerformanceLevel, Prescription
from webapp.patients.progress_store import rendered, summary_values
from webapp.recordings.models import AnalysisRun, Recording, RunReading
from webapp.recordings.reading import figures

EXERCISE_NAMES = ("Deep squat", "Sit to stand", "Shoulder abduction")
THERAPIST_PASSWORD = "large-clinic-therapist-pw"
COPY_ESCAPES = str.maketrans({"\\": "\\\\", "\t": "\\t", "\n": "\\n", "\r": "\\r"})
FAILURE = "The recording is too short: at least two repetitions are needed."
POINT_COLUMNS = ProgressPoint._meta.concrete_fields
REPORT_EVERY = 100_000  # rows between progress lines (a full fill takes a quarter of an hour)


class JsonText(str):
    """Text that is already JSON (a summary assembled from pre-serialised parts)."""


def copy_text(value, is_json: bool) -> str:
    """One value in PostgreSQL's COPY text format."""
    if value is None:
        return "\\N"
    if isinstance(value, bool):
        return "t" if value else "f"
    if isinstance(value, datetime.date | uuid.UUID | int | float) and not is_json:
        return value.isoformat() if isinstance(value, datetime.date) else str(value)
    if is_json and not isinstance(value, JsonText):
        value = json.dumps(value)
    return str(value).translate(COPY_ESCAPES)


class TableWriter:
    """Streams rows (dicts keyed by field attname) into one table; missing fields get defaults.

    Columns come from the model, so fields that other changes add with a default need no edit here.
    """

    def __init__(self, model: type[models.Model], batch: int = 2000) -> None:
        self.model = model
        self.fields = [
            f
            for f in model._meta.concrete_fields
            if not (f.primary_key and isinstance(f, models.AutoField | models.BigAutoField))
        ]
        self.batch = batch
        self.pending: list[dict] = []
        self.count = 0
        self.postgres = connection.vendor == "postgresql"

    def default(self, field: models.Field):
        if getattr(field, "auto_now", False) or getattr(field, "auto_now_add", False):
            return timezone.now()
        return field.get_default()

    def __enter__(self) -> TableWriter:
        self.cursor = connection.cursor()
        if self.postgres:
            columns = ", ".join(connection.ops.quote_name(f.column) for f in self.fields)
            table = connection.ops.quote_name(self.model._meta.db_table)
            self.copy_cm = self.cursor.cursor.copy(f"COPY {table} ({columns}) FROM STDIN")
            self.copy = self.copy_cm.__enter__()
        return self

    def add(self, row: dict) -> None:
        self.pending.append(row)
        self.count += 1
        if len(self.pending) >= self.batch:
            self.flush()

    def values(self, row: dict) -> Iterator:
        for field in self.fields:
            yield field, row[field.attname] if field.attname in row else self.default(field)

    def flush(self) -> None:
        if self.postgres:
            buffer = io.StringIO()
            for row in self.pending:
                cells = (copy_text(v, isinstance(f, models.JSONField)) for f, v in self.values(row))
                buffer.write("\t".join(cells) + "\n")
            self.copy.write(buffer.getvalue())
        else:
            self.insert_batch()
        self.pending = []

    def insert_batch(self) -> None:
        columns = ", ".join(connection.ops.quote_name(f.column) for f in self.fields)
        marks = ", ".join(["%s"] * len(self.fields))
        table = connection.ops.quote_name(self.model._meta.db_table)
        rows = [
            tuple(
                v if isinstance(v, JsonText) else f.get_db_prep_save(v, connection)
                for f, v in self.values(row)
            )
            for row in self.pending
        ]
        self.cursor.executemany(f"INSERT INTO {table} ({columns}) VALUES ({marks})", rows)

    def __exit__(self, *exc) -> None:
        if exc[0] is None:
            self.flush()
        if self.postgres:
            self.copy_cm.__exit__(*exc)
        self.cursor.close()


def set_bulk_session() -> None:
    """Faster bulk load: no wait for the WAL flush, and lz4 (not pglz) for the large summaries."""
    with connection.cursor() as cursor:
        cursor.execute("SET LOCAL synchronous_commit TO off")
        cursor.execute("SET LOCAL default_toast_compression TO 'lz4'")


class Command(BaseCommand):
    help = "Fill the database with a large synthetic clinic (patients, recordings, runs)."

    def add_arguments(self, parser):
        parser.add_argument("--patients", type=int, default=10_000)
        parser.add_argument("--runs", type=int, default=1_000_000)
        parser.add_argument("--therapists", type=int, default=50)
        parser.add_argument("--clinic", default="Large clinic")
        parser.add_argument("--seed", type=int, default=0)
        parser.add_argument(
            "--into-existing",
            action="store_true",
            help="Add to an existing clinic (with exercises of their own).",
        )

    def handle(self, *args, **options):
        if options["runs"] < options["patients"]:
            raise CommandError("--runs must be at least --patients (one run per patient).")
        exists = Clinic.objects.filter(name=options["clinic"]).exists()
        if exists and not options["into_existing"]:
            raise CommandError(f"A clinic named {options['clinic']!r} exists already.")
        if options["into_existing"] and not exists:
            raise CommandError(f"No clinic named {options['clinic']!r}.")
        started = time.perf_counter()
        with transaction.atomic():
            if connection.vendor == "postgresql":
                set_bulk_session()
            timings = Filler(options, self.stdout).fill()
        if connection.vendor == "postgresql":
            connection.cursor().execute("ANALYZE")
        total = time.perf_counter() - started
        for table, (rows, seconds) in timings.items():
            self.stdout.write(f"{table:<16} {rows:>10,} rows {seconds:8.1f} s")
        self.stdout.write(self.style.SUCCESS(f"Large clinic filled in {total:.1f} s"))


class Filler:
    """Writes one clinic's rows table by table, streaming each patient's uploads."""

    def __init__(self, options: dict, stdout) -> None:
        self.options = options
        self.stdout = stdout
        self.now = timezone.now()
        self.timings: dict[str, tuple[int, float]] = {}

    def fill(self) -> dict[str, tuple[int, float]]:
        self.clinic, _ = Clinic.objects.get_or_create(name=self.options["clinic"])
        # Ids are drawn from the seed: mixing in the clinic keeps two fills' ids apart.
        self.seed = self.options["seed"] * 7919 + self.clinic.pk
        self.counts = gen.runs_per_patient(
            self.options["runs"], self.options["patients"], self.seed
        )
        self.tails = [JsonText(t) for t in gen.summary_tails(self.seed)]
        self.exercises = self.make_exercises()
        self.therapists = self.make_therapists()
        rng = random.Random(self.seed)
        self.patient_ids = [gen.new_uuid(rng) for _ in self.counts]
        self.timed(Patient, self.patient_rows)
        self.timed(Patient.therapists.through, self.assignment_rows)
        self.timed(Prescription, self.prescription_rows)
        self.timed(Recording, self.recording_rows)
        self.timed(AnalysisRun, self.run_rows)
        self.timed(PerformanceLevel, self.level_rows)
        self.timed(ProgressPoint, self.point_rows)
        self.timed(RunReading, self.reading_rows)
        return self.timings

    def timed(self, model, rows) -> None:
        table = model._meta.db_table
        started = time.perf_counter()
        with TableWriter(model) as writer:
            for row in rows():
                writer.add(row)
                if writer.count % REPORT_EVERY == 0:
                    self.progress(table, writer.count, time.perf_counter() - started)
        self.timings[table] = (writer.count, time.perf_counter() - started)
        self.progress(table, writer.count, self.timings[table][1])

    def progress(self, table: str, rows: int, seconds: float) -> None:
        self.stdout.write(f"  {table}: {rows:,} rows in {seconds:.0f} s", ending="\n")
        self.stdout.flush()

    def point_rows(self) -> Iterator[dict]:
        """The progress point a worker stores when a run succeeds, rendered from the generated
        summary (reading a million summaries back would take longer than writing them)."""
        values = [summary_values(json.loads('{"score": 0, ' + tail)) for tail in self.tails]
        for index in range(len(self.patient_ids)):
            for upload in self.uploads(index):
                tail = values[upload.recording.int % len(self.tails)]
                for run_id, status in upload.runs:
                    if status == "succeeded":
                        point = rendered({**tail, "pk": run_id, "score": float(upload.score)})
                        yield {f.attname: getattr(point, f.attname) for f in POINT_COLUMNS}

    def reading_rows(self) -> Iterator[dict]:
        """The reading a worker stores when a run succeeds (`webapp.recordings.reading`), built
        once per generated summary; each run's own score beside it."""
        readings = []
        for tail in self.tails:
            data = json.loads('{"score": 0, ' + tail)
            found = figures(AnalysisSummary.from_json(data), data)
            for key in ("repetitions", "statements"):
                found[key] = JsonText(json.dumps(found[key]))
            readings.append(found)
        for index in range(len(self.patient_ids)):
            for upload in self.uploads(index):
                found = readings[upload.recording.int % len(self.tails)]
                for run_id, status in upload.runs:
                    if status == "succeeded":
                        score = float(upload.score) if found["fits"] else None
                        yield {**found, "run_id": run_id, "score": score}

    def make_exercises(self) -> list[tuple[Exercise, ExerciseModel]]:
        made = []
        # Into an existing clinic: exercises of their own, so that nothing that opens recording
        # files (similar recordings, exercise recognition) meets these file-less recordings.
        suffix = f" (synthetic {self.seed})" if self.options["into_existing"] else ""
        for base in EXERCISE_NAMES:
            name = base + suffix
            exercise = Exercise.objects.create(
                clinic=self.clinic,
                name=name,
                tutor_file=f"tutors/large-{name.lower().replace(' ', '-')}.bvh.gz",
                landmark_type_names={"1": "start", "2": "end of range"},
                involved_joints=list(gen.JOINTS),
                archived_at=self.now if suffix else None,  # not offered for new uploads
            )
            model = ExerciseModel.objects.create_next_version(
                exercise, status=ModelStatus.READY, progress=100
            )
            exercise.active_model = model
            exercise.save(update_fields=["active_model"])
            made.append((exercise, model))
        return made

    def make_therapists(self) -> list[User]:
        hashed = User(username="x")
        hashed.set_password(THERAPIST_PASSWORD)
        prefix = f"{self.clinic.pk}-{self.options['seed']}-therapist"
        users = [
            User(
                username=f"{prefix}-{i:03d}",
                clinic=self.clinic,
                role=Role.THERAPIST,
                password=hashed.password,
            )
            for i in range(self.options["therapists"])
        ]
        User.objects.bulk_create(users)
        return list(User.objects.filter(username__startswith=prefix).order_by("username"))

    def uploads(self, index: int) -> Iterator[gen.Upload]:
        return gen.patient_uploads(
            self.seed, index, self.counts[index], len(self.exercises), self.now
        )

    def patient_rows(self) -> Iterator[dict]:
        rng = random.Random(self.seed + 1)
        for index, pk in enumerate(self.patient_ids):
            last = max(u.at for u in self.uploads(index))
            yield {
                "id": pk,
                "clinic_id": self.clinic.pk,
                "display_name": gen.patient_name(rng, index),
                "date_of_birth": datetime.date(rng.randint(1935, 2010), rng.randint(1, 12), 1),
                "notes": rng.choice(("", "", "Knee rehabilitation.", "Post-operative shoulder.")),
                "created_at": self.now - datetime.timedelta(days=gen.DAYS_OF_HISTORY + 1),
                "last_activity_at": last,
                "archived_at": self.now if rng.random() < 0.05 else None,
            }

    def assignment_rows(self) -> Iterator[dict]:
        for index, pk in enumerate(self.patient_ids):
            therapist = self.therapists[index % len(self.therapists)]
            yield {"patient_id": pk, "user_id": therapist.pk}

    def prescription_rows(self) -> Iterator[dict]:
        rng = random.Random(self.seed + 2)
        start = (self.now - datetime.timedelta(days=gen.DAYS_OF_HISTORY)).date()
        for pk in self.patient_ids:
            for exercise, _ in rng.sample(self.exercises, rng.randint(1, 2)):
                yield {
                    "id": gen.new_uuid(rng),
                    "patient_id": pk,
                    "exercise_id": exercise.pk,
                    "start_date": start,
                    "created_at": self.now,
                }

    def recording_rows(self) -> Iterator[dict]:
        for index, pk in enumerate(self.patient_ids):
            therapist = self.therapists[index % len(self.therapists)]
            for upload in self.uploads(index):
                yield {
                    "id": upload.recording,
                    "clinic_id": self.clinic.pk,
                    "patient_id": pk,
                    "exercise_id": self.exercises[upload.exercise][0].pk,
                    "file": f"recordings/large/{upload.recording}.bvh.gz",
                    "original_name": "session.bvh.gz",
                    "checksum": upload.recording.hex * 2,
                    "size_bytes": 180_000,
                    "n_frames": 900,
                    "n_joints": 22,
                    "fps": 30.0,
                    "duration_s": 30.0,
                    "pain_score": upload.recording.int % 11,
                    "uploaded_by_id": therapist.pk,
                    "uploaded_at": upload.at,
                }

    def run_rows(self) -> Iterator[dict]:
        for index in range(len(self.patient_ids)):
            for upload in self.uploads(index):
                model = self.exercises[upload.exercise][1]
                for position, (run_id, status) in enumerate(upload.runs):
                    yield self.run_row(upload, model, position, run_id, status)

    def run_row(self, upload, model, position: int, run_id, status: str) -> dict:
        created = upload.at + datetime.timedelta(hours=position)
        succeeded = status == "succeeded"
        tail = self.tails[upload.recording.int % len(self.tails)]
        return {
            "id": run_id,
            "recording_id": upload.recording,
            "model_id": model.pk if succeeded else None,
            "code_version": "0.1.0",
            "status": status,
            "stage": "done" if succeeded else "failed",
            "progress": 100 if succeeded else 0,
            "attempts": 1,
            "worker": "large-clinic-fill",
            "created_at": created,
            "started_at": created + datetime.timedelta(seconds=1),
            "finished_at": created + datetime.timedelta(seconds=3),
            "user_error": "" if succeeded else FAILURE,
            "summary": JsonText(f'{{"score": {upload.score}, {tail}') if succeeded else {},
            "score": float(upload.score) if succeeded else None,
        }

    def level_rows(self) -> Iterator[dict]:
        rng = random.Random(self.seed + 3)
        for index, pk in enumerate(self.patient_ids):
            used = sorted({u.exercise for u in self.uploads(index)})
            for exercise_index in used:
                for joint in gen.JOINTS:
                    yield {
                        "patient_id": pk,
                        "exercise_id": self.exercises[exercise_index][0].pk,
                        "joint": joint,
                        "gamma": round(rng.uniform(0.2, 1.0), 4),
                        "updated_at": self.now,
                    }
