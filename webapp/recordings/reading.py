"""The one reading of a run: one verdict per repetition, one pass count, one set of statements.

Every page, report, export and API answer about a succeeded run reads its `RunReading` (the
figures: fits, score, repetition and pass counts; the words: a verdict sentence and the reasons of
each repetition, what to correct, what went well, what the therapist changed) instead of deciding
again from the stored summary. The rules live here and nowhere else:

- `verdict`: a therapist's label on a repetition first, else the analysis' own verdict, else (a run
  stored before verdicts) its score against the run's threshold;
- `shown_score`: a repetition's score as a whole number that never crosses the threshold by
  rounding (69.6 is shown 69 beside "not passed", never 70);
- "nothing to correct" only when every repetition passed: a failed repetition without any
  correction naming it brings its own reason into what to correct.

A reading is built when its run ends (`workers.runs` through `precompute.refresh_after_run`), when
a therapist corrects the run (`webapp.recordings.corrections`), and by the first reader that finds
none (runs stored before readings, runs written by bulk loads); writing a run's summary or a
correction drops it (`webapp.recordings.models.ReadingSource`), so a stale reading is never read.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from django.db.models import Count, QuerySet, Subquery

from analysis.pipeline.results import AnalysisSummary, RepetitionResult
from webapp.recordings.models import (
    AnalysisRun,
    AssessmentCorrection,
    LandmarkCorrection,
    RepetitionLabel,
    RunReading,
    RunStatus,
)

RULE = 1  # raise when the rules below change: older readings are then built again on read
THERAPIST, ANALYSIS = "therapist", "analysis"
# Paper 001's guidance types as the therapist reads them (the reason of a run stored before
# reasons: its guidance).
GUIDANCE_WORDS = {
    "too fast": "too fast",
    "too slow": "too slow",
    "overdone": "went too far",
    "incomplete": "did not reach far enough",
}
THERAPIST_REASON = "Not done well, in the therapist's judgement."
FIELDS = [
    "rule", "fits", "score", "repetition_count", "passed_count", "labelled_count",
    "repetitions", "statements",
]  # fmt: skip


def guidance_words(kind: str) -> str:
    return GUIDANCE_WORDS.get(kind, kind.replace("_", " "))


def verdict(rep: RepetitionResult, threshold: float, label: bool | None) -> tuple[bool, str]:
    """(passed, by whom): the therapist's label first, then the analysis."""
    if label is not None:
        return bool(label), THERAPIST
    return rep.analysis_verdict(threshold), ANALYSIS


def shown_score(score: float, threshold: float) -> int:
    """The whole number shown for a score: rounded, except that a score under the threshold is
    never rounded up onto it (one comparison everywhere: what is shown agrees with the rule)."""
    whole = round(score)
    if score < threshold <= whole:
        return math.ceil(threshold) - 1
    return whole


def verdict_sentence(passed: bool, by: str, score: int, threshold: float) -> str:
    """'passed (score 74, needs 70)'; a therapist's verdict says so."""
    word = "passed" if passed else "not passed"
    if by == THERAPIST:
        return f"{word}: the therapist's verdict (analysis score {score}, needs {threshold:.0f})"
    return f"{word} (score {score}, needs {threshold:.0f})"


def reasons_of(rep: RepetitionResult, stored: Mapping[str, Any], passed: bool, by: str) -> list:
    """The sentences of one repetition: the analysis' reasons (older runs: their guidance), and
    the therapist's verdict when they failed a repetition the analysis did not give a reason for."""
    if passed and by == THERAPIST:  # the therapist passed it: the analysis' objections fall
        return []
    found = getattr(rep, "reasons", None)
    if found is None:
        kept = stored.get("reasons")
        found = kept if isinstance(kept, list) else ()
    reasons = [str(text) for text in found if text]
    if not reasons and not passed:
        reasons = [f"Movement {guidance_words(g.type)}." for g in rep.guidance]
    if not passed and by == THERAPIST and not reasons:
        reasons = [THERAPIST_REASON]
    return reasons


def repetition_rows(
    result: AnalysisSummary, stored: list[Any], labels: Mapping[int, bool]
) -> list[dict[str, Any]]:
    """Each repetition's verdict, by whom, its shown score, sentence and reasons (``stored``:
    the summary's raw repetitions, for reasons the typed result may not carry)."""
    threshold = result.pass_threshold
    rows = []
    for i, rep in enumerate(result.repetitions):
        passed, by = verdict(rep, threshold, labels.get(i))
        raw = stored[i] if i < len(stored) and isinstance(stored[i], dict) else {}
        score = shown_score(rep.score, threshold)
        rows.append(
            {
                "number": i + 1, "score": round(rep.score, 1), "shown_score": score,
                "passed": passed, "by": by,
                "verdict": verdict_sentence(passed, by, score, threshold),
                "reasons": reasons_of(rep, raw, passed, by),
            }
        )  # fmt: skip
    return rows


def to_correct(result: AnalysisSummary, rows: list[dict[str, Any]]) -> list[str]:
    """What to correct (older runs: their feedback); every failed repetition no correction names
    adds its first reason, so "nothing to correct" is only said when every repetition passed."""
    advice = result.advice
    if advice.corrections or advice.went_well or not result.feedback:
        texts = [item.text for item in advice.corrections]
    else:
        texts = [comment.text for comment in result.feedback]
    named = {n for item in advice.corrections for n in item.repetitions}
    for row in rows:
        if not row["passed"] and row["number"] not in named and row["reasons"]:
            texts.append(f"Repetition {row['number']}: {row['reasons'][0]}")
    return texts


@dataclass(frozen=True)
class Corrections:
    """What a therapist corrected on one run: verdicts by repetition index, key poses placed
    again, how many joint levels changed."""

    labels: Mapping[int, bool] = field(default_factory=dict)
    moved_key_poses: bool = False
    levels: int = 0


def corrections_of(run_ids: list[Any]) -> dict[Any, Corrections]:
    """The corrections of these runs (three queries whatever their number)."""
    labels: dict[Any, dict[int, bool]] = defaultdict(dict)
    found = RepetitionLabel.objects.filter(run_id__in=run_ids)
    for run_id, index, passed in found.values_list("run_id", "index", "passed"):
        labels[run_id][index] = passed
    moved = set(
        LandmarkCorrection.objects.filter(run_id__in=run_ids).values_list("run_id", flat=True)
    )
    levels = dict(
        AssessmentCorrection.objects.filter(run_id__in=run_ids)
        .values("run_id")
        .annotate(n=Count("id"))
        .values_list("run_id", "n")
    )
    return {pk: Corrections(labels.get(pk, {}), pk in moved, levels.get(pk, 0)) for pk in run_ids}


def therapist_changes(fixes: Corrections) -> list[str]:
    """The therapist's corrections of the analysis, in plain words."""
    changes = []
    if fixes.moved_key_poses:
        changes.append("The key poses were placed again by the therapist.")
    if fixes.levels:
        changes.append(f"{fixes.levels} joint assessment(s) changed by the therapist.")
    for index in sorted(fixes.labels):
        word = "passed" if fixes.labels[index] else "not passed"
        changes.append(f"Repetition {index + 1} marked {word} by the therapist.")
    return changes


def figures(
    result: AnalysisSummary, stored: Mapping[str, Any], fixes: Corrections = Corrections()
) -> dict[str, Any]:
    """Every field of a reading, from a result (``stored``: its JSON as the run holds it) and
    the therapist's corrections of it."""
    labels = {i: p for i, p in fixes.labels.items() if i < result.repetition_count}
    rows = repetition_rows(result, stored.get("repetitions") or [], labels)
    fits = result.match.fits
    return {
        "rule": RULE,
        "fits": fits,
        "score": result.score if fits else None,
        "repetition_count": result.repetition_count,
        "passed_count": sum(row["passed"] for row in rows),
        "labelled_count": len(labels),
        "repetitions": rows,
        "statements": {
            "message": "" if fits else result.match.message,
            "to_correct": to_correct(result, rows),
            "went_well": list(result.advice.went_well),
            "therapist": therapist_changes(
                Corrections(labels, fixes.moved_key_poses, fixes.levels)
            ),
        },
    }


def build_many(runs: Iterable[AnalysisRun]) -> dict[Any, RunReading]:
    """Build and store the readings of these succeeded runs (five queries whatever their
    number); keyed by run id. A run whose summary cannot be read gets none (its pages say so)."""
    ready = [
        (run, result)
        for run in runs
        if run.status == RunStatus.SUCCEEDED and (result := run.result) is not None
    ]
    fixes = corrections_of([run.pk for run, _ in ready])
    readings = {
        run.pk: RunReading(run_id=run.pk, **figures(result, run.summary, fixes[run.pk]))
        for run, result in ready
    }
    # A worker and a page may build the same run at once: both write the same figures.
    RunReading.objects.bulk_create(
        readings.values(), batch_size=500, update_conflicts=True, unique_fields=["run"],
        update_fields=[*FIELDS, "built_at"],
    )  # fmt: skip
    for run, _ in ready:
        run._state.fields_cache["reading"] = readings[run.pk]
    return readings


def build(run: AnalysisRun) -> RunReading | None:
    """Build and store the reading of a succeeded run (None for any other run, whose reading, if
    one was left, is dropped)."""
    if run.status != RunStatus.SUCCEEDED or run.result is None:
        RunReading.objects.filter(run_id=run.pk).delete()
        return None
    return build_many([run]).get(run.pk)


def build_for(run_id: Any) -> RunReading | None:
    run = AnalysisRun.objects.filter(pk=run_id).first()
    return build(run) if run is not None else None


def reading_of(run: AnalysisRun | None) -> RunReading | None:
    """The run's reading, built on this first read when it has none (or one of an older rule)."""
    if run is None or run.status != RunStatus.SUCCEEDED:
        return None
    try:
        stored = run.reading
    except RunReading.DoesNotExist:
        stored = None
    if stored is not None and stored.rule == RULE:
        return stored
    return build(run)


def readings_of(run_ids: Iterable[Any]) -> dict[Any, RunReading]:
    """The readings of these runs, keyed by run id: stored ones in one query, missing ones of
    succeeded runs built now in a few more (only once: then they are stored)."""
    ids = [pk for pk in run_ids if pk is not None]
    found = {r.run_id: r for r in RunReading.objects.filter(run_id__in=ids, rule=RULE)}
    missing = [pk for pk in ids if pk not in found]
    if missing:
        found |= build_many(AnalysisRun.objects.filter(pk__in=missing, status=RunStatus.SUCCEEDED))
    return found


def store_missing(runs: QuerySet[AnalysisRun], batch: int = 1000) -> int:
    """Build the readings the succeeded runs in ``runs`` lack (after a bulk load, or to build
    them all ahead of the first reads); returns how many were built."""
    todo = runs.filter(status=RunStatus.SUCCEEDED).exclude(reading__rule=RULE).order_by()
    ids = list(todo.values_list("pk", flat=True))
    for start in range(0, len(ids), batch):
        build_many(AnalysisRun.objects.filter(pk__in=ids[start : start + batch]))
    return len(ids)


def figure_annotations(newest: QuerySet[AnalysisRun]) -> dict[str, Subquery]:
    """What a list reads of each row's newest run (``newest``: runs of ``OuterRef("pk")``, newest
    first): its reading's stored figures, never the summary's JSON."""
    return {
        f"run_{name}": Subquery(newest.values(f"reading__{field}")[:1])
        for name, field in (
            ("fits", "fits"), ("passed", "passed_count"),
            ("repetitions", "repetition_count"), ("rule", "rule"),
        )
    }  # fmt: skip


def with_figures(rows: Iterable[Any]) -> list[Any]:
    """List rows annotated with `figure_annotations` (and ``run_id``, ``run_status``): rows
    whose succeeded run has no current reading get it built now and their figures filled in.
    Returns the rows as a list."""
    rows = list(rows)
    stale = [r for r in rows if r.run_status == RunStatus.SUCCEEDED and r.run_rule != RULE]
    built = readings_of([r.run_id for r in stale])
    for row in stale:
        reading = built.get(row.run_id)
        if reading is not None:
            row.run_fits, row.run_passed = reading.fits, reading.passed_count
            row.run_repetitions, row.run_rule = reading.repetition_count, reading.rule
    return rows


def served_summary(run: AnalysisRun, reading: RunReading | None) -> dict[str, Any]:
    """A run's result as the API serves it: the typed result's JSON, each repetition's
    ``passed`` the reading's verdict (a therapist's label is the verdict everywhere)."""
    body = AnalysisSummary.from_json(run.summary or {}).to_json()
    if reading is not None:
        for rep, row in zip(body.get("repetitions", []), reading.repetitions, strict=False):
            rep["passed"] = row["passed"]
    return body


def attach_readings(recordings: Iterable[Any]) -> None:
    """Give each recording of a list (runs prefetched) the reading of its newest succeeded run
    as ``run_reading`` (None without one): one query for the page, missing ones built once."""
    newest = [(recording, recording.latest_succeeded_run()) for recording in recordings]
    found = readings_of(run.pk for _, run in newest if run is not None)
    for recording, run in newest:
        recording.run_reading = found.get(run.pk) if run is not None else None
