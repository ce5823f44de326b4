"""A page of recordings with their newest run's figures, in one query.

Correlated subqueries read the newest run's id, status, progress and score columns and two small
values the database extracts from its summary (the repetition count and how many passed), so
neither the 10–20 kB summaries nor one query per recording reach Python. `with_result` adds the
newest run's summary itself (`?fields=result`).
"""

from __future__ import annotations

from django.db.models import F, Func, IntegerField, OuterRef, QuerySet, Subquery
from django.db.models.fields.json import KeyTransform

from webapp.recordings.models import AnalysisRun, Recording


class PassedCount(Func):
    """How many items of summary.repetitions have `"passed": true` (NULL without a summary)."""

    output_field = IntegerField()
    template = (
        "(SELECT COUNT(*) FROM json_each(%(expressions)s, '$.repetitions') "
        "WHERE json_extract(value, '$.passed') = 1)"
    )

    def as_postgresql(self, compiler, connection, **extra_context):
        template = (
            "JSONB_ARRAY_LENGTH(JSONB_PATH_QUERY_ARRAY(%(expressions)s, "
            "'$.repetitions[*] ? (@.passed == true)'))"
        )
        return self.as_sql(compiler, connection, template=template, **extra_context)


def recording_summaries(recordings: QuerySet[Recording], with_result: bool = False):
    newest = AnalysisRun.objects.filter(recording_id=OuterRef("pk")).order_by("-created_at")
    annotated = recordings.select_related(None).annotate(
        exercise_name=F("exercise__name"),
        run_id=Subquery(newest.values("pk")[:1]),
        run_status=Subquery(newest.values("status")[:1]),
        run_progress=Subquery(newest.values("progress")[:1]),
        run_score=Subquery(newest.values("score")[:1]),
        run_repetitions=Subquery(
            newest.annotate(n=KeyTransform("repetition_count", "summary")).values("n")[:1],
            output_field=IntegerField(),
        ),
        run_passed=Subquery(newest.annotate(n=PassedCount("summary")).values("n")[:1]),
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
