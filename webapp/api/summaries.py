"""A page of recordings with their newest run's figures, in one query.

Correlated subqueries read the newest run's id, status, progress and score columns and its
reading's stored figures (`webapp.recordings.reading`: fits, repetition count, how many passed,
the therapist's verdicts counted), so neither the 10–20 kB summaries nor one query per recording
reach Python; rows whose run has no reading yet get it built (`reading.with_figures`, once).
`with_result` adds the newest run's summary itself (`?fields=result`).
"""

from __future__ import annotations

from django.db.models import F, OuterRef, QuerySet, Subquery

from webapp.recordings.models import AnalysisRun, Recording
from webapp.recordings.reading import figure_annotations


def recording_summaries(recordings: QuerySet[Recording], with_result: bool = False):
    newest = AnalysisRun.objects.filter(recording_id=OuterRef("pk")).order_by("-created_at")
    annotated = recordings.select_related(None).annotate(
        exercise_name=F("exercise__name"),
        run_id=Subquery(newest.values("pk")[:1]),
        run_status=Subquery(newest.values("status")[:1]),
        run_progress=Subquery(newest.values("progress")[:1]),
        run_score=Subquery(newest.values("score")[:1]),
        **figure_annotations(newest),
    )
    if with_result:
        annotated = annotated.annotate(run_summary=Subquery(newest.values("summary")[:1]))
    return annotated.only(
        "pk",
        "clinic_id",
        "patient_id",
        "exercise_id",
        "original_name",
        "uploaded_at",
        "n_frames",
        "fps",
        "duration_s",
        "pain_score",
    )
