"""The pipeline: the exercise model (fitting, file format), the stages in order, typed results.

`analyse` runs the stages in the order of `stage_order.ORDER`, the one list of them; workers and
the command line (`analysis/__main__.py`) call it.
"""

from analysis.pipeline.match import Candidate, MatchContext  # whether a recording fits (match.py)
from analysis.pipeline.model import (
    FittedModel,
    ModelVersionError,
    build_model,
    dump_model,
    load_model,
)
from analysis.pipeline.model_fit import ModelComponents, TrainingRecording, TutorKeyPosesError
from analysis.pipeline.results import (
    AnalysisSummary,
    AngleRange,
    ExerciseMatch,
    KeyPose,
    RepetitionResult,
)
from analysis.pipeline.run import AnalysisResult, analyse

__all__ = [
    "AnalysisResult",
    "AnalysisSummary",
    "AngleRange",
    "Candidate",
    "ExerciseMatch",
    "FittedModel",
    "KeyPose",
    "MatchContext",
    "ModelComponents",
    "ModelVersionError",
    "RepetitionResult",
    "TrainingRecording",
    "TutorKeyPosesError",
    "analyse",
    "build_model",
    "dump_model",
    "load_model",
]
