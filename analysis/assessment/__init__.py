"""Assessment: repetition scores, per-joint levels at each key pose, performance level.

Pipeline: after the repetitions are found, each is scored (`repetition_features`, the model's
scorer), each key pose is assessed per joint, and the patient's level per joint is updated.
"""

from analysis.assessment.joints import (
    LandmarkAssessor,
    ThresholdAssessor,
    joint_relevance,
    landmark_features,
    tutor_mean_poses,
)
from analysis.assessment.performance_level import update_levels
from analysis.assessment.scoring import RepetitionScorer, fit_scorer, repetition_features

__all__ = [
    "LandmarkAssessor",
    "RepetitionScorer",
    "ThresholdAssessor",
    "fit_scorer",
    "joint_relevance",
    "landmark_features",
    "repetition_features",
    "tutor_mean_poses",
    "update_levels",
]
