"""The pipeline: the exercise model (fitting, file format), the stages in order, the command line.

`analyse` is the only place the stage order lives; workers and the command line call it.
"""

from analysis.pipeline.model import (
    FittedModel,
    ModelVersionError,
    build_model,
    dump_model,
    load_model,
)
from analysis.pipeline.model_fit import ModelComponents, TrainingRecording
from analysis.pipeline.results import AnalysisSummary, AngleRange, KeyPose, RepetitionResult
from analysis.pipeline.run import AnalysisResult, analyse

__all__ = [
    "AnalysisResult",
    "AnalysisSummary",
    "AngleRange",
    "FittedModel",
    "KeyPose",
    "ModelComponents",
    "ModelVersionError",
    "RepetitionResult",
    "TrainingRecording",
    "analyse",
    "build_model",
    "dump_model",
    "load_model",
]
