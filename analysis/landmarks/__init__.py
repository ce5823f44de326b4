"""Key poses: motion signature, frame features, landmark identification, refining, repetitions
from a landmark sequence, their evaluation, and the progress-axis segmenter.

Pipeline: repetitions are cut with `segment` on the exercise's progress axis; the annotation page
suggests a new tutor's key poses with `suggest_key_poses`.
"""

from analysis.landmarks.key_poses import KeyPoses
from analysis.landmarks.segmentation import ProgressAxis, Segments, fit_axis, segment
from analysis.landmarks.suggestions import suggest_key_poses

__all__ = ["KeyPoses", "ProgressAxis", "Segments", "fit_axis", "segment", "suggest_key_poses"]
