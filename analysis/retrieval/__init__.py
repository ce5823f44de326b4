"""Fast motion retrieval with 2-bit quantised PCA features (body-part distances per frame).

Not a pipeline stage: the recording page's "similar recordings" and exercise identification use it.
"""

from analysis.retrieval.features import recording_features
from analysis.retrieval.quantised import MotionRetriever

__all__ = ["MotionRetriever", "recording_features"]
