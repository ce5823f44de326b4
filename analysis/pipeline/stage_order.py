"""The stages of one analysis, in the order `analysis.pipeline.run.analyse` runs them: the one
list of that order. The progress bar's words and fractions, the ``timings_ms`` keys and the stage
diagram of docs/ARCHITECTURE.md (`docs/stage_diagram.py` writes it) all come from `ORDER`;
`StageOrder` refuses a stage run out of this order, so the code cannot drift from the list.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Stage:
    """One stage: ``key`` names it in ``timings_ms``; ``label`` is what the progress bar says
    while it runs (therapists read it); ``done_by`` is the module doing its work; ``if_unfit``:
    it still runs for a recording that does not show the exercise (no repetition, no score)."""

    key: str
    label: str
    done_by: str
    if_unfit: bool = False


ORDER: tuple[Stage, ...] = (
    Stage("prepare", "reading the recording", "analysis.pipeline.prepare"),
    Stage("landmark_identification", "finding key poses", "analysis.landmarks.identification"),
    Stage("landmark_refining", "placing key poses precisely", "analysis.landmarks.refining"),
    Stage("periodic_analysis", "checking the order of key poses", "analysis.pipeline.keyposes"),
    Stage("repetitions", "counting repetitions", "analysis.pipeline.keyposes"),
    Stage("match", "checking that the recording shows the exercise", "analysis.pipeline.match"),
    Stage(
        "synchronisation", "matching the reference in time", "analysis.pipeline.repetition_stage"
    ),
    Stage("alignment", "comparing each repetition", "analysis.pipeline.gestures"),
    # before the scores: a clearly missed key pose caps its repetition
    Stage("assessment", "assessing each key pose", "analysis.pipeline.stages"),
    Stage("scores", "scoring repetitions", "analysis.pipeline.stages"),
    Stage("performance_level", "updating the level", "analysis.pipeline.stages"),
    Stage("adjustment", "preparing the playback", "analysis.pipeline.stages", if_unfit=True),
    Stage("clinical_angles", "measuring joint angles", "analysis.clinical", if_unfit=True),
    # after the angles: corrections compare them with the tutor's
    Stage("feedback", "writing feedback", "analysis.pipeline.stages", if_unfit=True),
    Stage(
        "workspace", "measuring the reach of each hand", "analysis.pipeline.clinical_stage", True
    ),
)


class StageOrderError(RuntimeError):
    """A stage run that `ORDER` does not know or places before one already run: a programming
    error (not bad input), so it is no ValueError the command line would report as exit 2."""


class StageOrder:
    """Follows one analysis through `ORDER`: where each stage sits (its progress fraction, its
    label) and that each comes after the one before it."""

    def __init__(self, order: tuple[Stage, ...] = ORDER) -> None:
        self.order = order
        self.position = {stage.key: k for k, stage in enumerate(order)}
        self.last = -1

    def enter(self, key: str) -> Stage:
        """The stage ``key`` starts; raises `StageOrderError` when it is out of order."""
        k = self.position.get(key)
        if k is None or k <= self.last:
            raise StageOrderError(f"stage {key!r} out of the order in stage_order.ORDER")
        self.last = k
        return self.order[k]

    def fraction(self, key: str) -> float:
        """The share of the stages before ``key`` (what the progress bar shows as it starts)."""
        return self.position[key] / len(self.order)
