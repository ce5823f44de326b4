"""An exercise is defined by its tutor (reference) recording and its key poses."""

from __future__ import annotations

import uuid

from django.core.files.base import ContentFile
from django.db import models, transaction
from django.db.models import Max

from analysis.bvh import Motion, dumps, read
from analysis.landmarks import suggest_key_poses
from analysis.sources import SUFFIXES, read_recording
from analysis.sources.video import SUFFIXES as VIDEO_SUFFIXES
from analysis.sources.video import Progress
from webapp.accounts.models import Clinic

# A reference video's motion, solved once (the pose estimator takes ~30 ms a frame, too long for
# every page and analysis) and stored beside the video as BVH text under this ending.
SOLVED_VIDEO = ".motion.bvh"
# The capture source a reference's file ending names, when the ending alone tells it.
KIND_BY_ENDING = {".trc": "trc", ".c3d": "c3d", **{s: "video" for s in VIDEO_SUFFIXES}}


class Exercise(models.Model):
    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    clinic = models.ForeignKey(Clinic, on_delete=models.PROTECT, related_name="exercises")
    name = models.CharField(max_length=200)
    description = models.TextField(blank=True)
    tutor_file = models.FileField(upload_to="tutors/")
    tutor_checksum = models.CharField(max_length=64, blank=True)
    # Key poses of the tutor: frame numbers and landmark type ids, in time order.
    tutor_landmark_frames = models.JSONField(default=list, blank=True)
    tutor_landmark_types = models.JSONField(default=list, blank=True)
    # {"1": "start", "2": "end of range"}: names shown to therapists and used in feedback.
    landmark_type_names = models.JSONField(default=dict, blank=True)
    involved_joints = models.JSONField(default=list, blank=True)
    # A replaced reference's key poses are suggested from its own recording: no model version is
    # built from them (the previous one stays in use) until the therapist confirms them.
    key_poses_to_confirm = models.BooleanField(default=False)
    feedback_grammar = models.TextField(blank=True)
    active_model = models.ForeignKey(
        "exercises.ExerciseModel",
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="+",
    )
    # Paper 001's pass/fail score threshold, refitted by Celery beat from therapist labels.
    pass_threshold = models.FloatField(null=True, blank=True)
    threshold_report = models.JSONField(default=dict, blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    archived_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["name"]
        constraints = [
            models.UniqueConstraint(fields=["clinic", "name"], name="exercise_name_per_clinic")
        ]

    def __str__(self) -> str:
        return self.name

    def tutor_motion(self, progress: Progress | None = None) -> Motion:
        """The tutor recording as a motion, whatever it was captured with (read once per
        instance and tutor file; a video once at all, see `read_video_tutor`). ``progress``
        hears the share of a video's frames read. Raises what `read_recording` and the storage
        raise (BVHError, OSError)."""
        return self.read_tutor(progress)[0]

    def read_tutor(self, progress: Progress | None = None) -> tuple[Motion, str]:
        """The tutor's motion and its capture source's kind ("bvh", "kinect", "video", ...)."""
        cached = self.__dict__.get("_tutor_motion")
        if cached is None or cached[0] != self.tutor_file.name:
            if self.tutor_is_video:
                cached = (self.tutor_file.name, self.read_video_tutor(progress), "video")
            else:
                cached = (self.tutor_file.name, *self.read_tutor_file())
            self.__dict__["_tutor_motion"] = cached
        return cached[1], cached[2]

    def read_tutor_file(self) -> tuple[Motion, str]:
        with self.tutor_file.open("rb") as handle:
            content = handle.read()
        if not self.tutor_file.name.lower().endswith(SUFFIXES):
            return read(content), "bvh"  # stored before other sources, under another ending
        imported = read_recording(self.tutor_file.name, content)
        return imported.motion, imported.report.kind

    @property
    def tutor_is_video(self) -> bool:
        return self.tutor_file.name.lower().endswith(VIDEO_SUFFIXES)

    @property
    def solved_video_name(self) -> str:
        return self.tutor_file.name + SOLVED_VIDEO

    @property
    def followable_live(self) -> bool:
        """A new live session can follow it: in use (not archived) with a model built, since
        every frame is aligned with the model."""
        return self.active_model_id is not None and self.archived_at is None

    def tutor_ready(self) -> bool:
        """False while a reference video waits for the worker to find the person in it."""
        storage = self.tutor_file.storage
        return not self.tutor_is_video or storage.exists(self.solved_video_name)

    def tutor_kind(self) -> str:
        """What the reference was captured with (`analysis.sources.RecordingSource.kind`); read
        from the file only when its ending does not say (.csv: Kinect or MediaPipe, ...)."""
        name = self.tutor_file.name.lower()
        ending = next((e for e in KIND_BY_ENDING if name.endswith(e)), None)
        if ending is not None:
            return KIND_BY_ENDING[ending]
        if not name.endswith((".csv", ".json", ".txt")):
            return "bvh"
        return self.read_tutor()[1]

    def read_video_tutor(self, progress: Progress | None) -> Motion:
        """The reference video's motion: stored as BVH once solved (normally by the worker's
        model build, which enqueueing the new reference starts). The first reading also puts
        in suggested key poses when the marked ones do not fit it (as a new reference file
        does), so the build it runs in can fit a model."""
        storage = self.tutor_file.storage
        if storage.exists(self.solved_video_name):
            with storage.open(self.solved_video_name, "rb") as handle:
                return read(handle.read())
        with self.tutor_file.open("rb") as handle:
            content = handle.read()
        motion = read_recording(self.tutor_file.name, content, progress or self.reading).motion
        self.take_key_poses(motion)
        if self.pk is not None:
            fields = ["tutor_landmark_frames", "tutor_landmark_types", "landmark_type_names"]
            self.save(update_fields=[*fields, "involved_joints"])
        if not storage.exists(self.solved_video_name):
            storage.save(self.solved_video_name, ContentFile(dumps(motion).encode()))
        return motion

    def reading(self, fraction: float) -> None:
        """The share of a reference video read, shown as the progress of this exercise's model
        builds under way (the worker's build reads the video first; fitting takes seconds)."""
        builds = ExerciseModel.objects.filter(exercise_id=self.pk, status=ModelStatus.RUNNING)
        builds.update(progress=max(1, int(80 * fraction)))

    def take_key_poses(self, motion: Motion) -> bool:
        """Key poses for a new reference ``motion``, set on this row (not saved): the marked
        ones when they fit its length, else the suggested ones (the page asks to check them).
        Joints the new reference lacks are dropped. True when the marked ones were kept."""
        frames = list(self.tutor_landmark_frames)
        # A replaced reference never keeps the frames marked on the old recording.
        kept = bool(frames) and max(frames) < motion.frames.shape[0]
        kept = kept and not self.key_poses_to_confirm
        if not kept:
            suggestion = suggest_key_poses(motion)
            earlier = self.landmark_type_names or {}
            self.tutor_landmark_frames = suggestion.frames.tolist()
            self.tutor_landmark_types = suggestion.types.tolist()
            self.landmark_type_names = {
                str(t): earlier[str(t)]
                for t in sorted(set(suggestion.types.tolist()))
                if earlier.get(str(t))
            }
        names = set(motion.skeleton.names)
        self.involved_joints = [j for j in self.involved_joints if j in names]
        return kept


class ModelStatus(models.TextChoices):
    QUEUED = "queued", "Queued"
    RUNNING = "running", "Building"
    READY = "ready", "Ready"
    FAILED = "failed", "Failed"


class ExerciseModelManager(models.Manager["ExerciseModel"]):
    def create_next_version(self, exercise: Exercise, **fields) -> ExerciseModel:
        """A new row numbered one above the exercise's latest version (1 for the first).

        Takes a lock on the exercise row, so two builds never get the same number.
        """
        with transaction.atomic():
            locked = Exercise.objects.select_for_update().get(pk=exercise.pk)
            latest = self.filter(exercise=locked).aggregate(v=Max("version"))["v"] or 0
            return self.create(exercise=locked, version=latest + 1, **fields)


class ExerciseModel(models.Model):
    """One built version of an exercise's model; the exercise names its active version."""

    id = models.UUIDField(primary_key=True, default=uuid.uuid4, editable=False)
    exercise = models.ForeignKey(Exercise, on_delete=models.CASCADE, related_name="models")
    version = models.PositiveIntegerField()
    status = models.CharField(
        max_length=10, choices=ModelStatus.choices, default=ModelStatus.QUEUED
    )
    progress = models.PositiveSmallIntegerField(default=0)
    artefact = models.FileField(upload_to="models/", blank=True)
    training_report = models.JSONField(default=dict, blank=True)
    code_version = models.CharField(max_length=40, blank=True)
    error = models.TextField(blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    finished_at = models.DateTimeField(null=True, blank=True)

    objects = ExerciseModelManager()

    class Meta:
        ordering = ["-version"]
        constraints = [
            models.UniqueConstraint(fields=["exercise", "version"], name="one_model_version")
        ]
