"""Streaming alignment, one frame at a time: Open-End DTW and its weighted, path-length-weighted
variant, and gesture-based DTW with its Bayes pass threshold.

Pipeline: the exercise model's pass threshold is fitted with `BayesThreshold` when training.
Live sessions (`analysis.live`) run these aligners on each streamed frame.
"""

from analysis.online.aligners import OpenEndAligner
from analysis.online.gbdtw import BayesThreshold

__all__ = ["BayesThreshold", "OpenEndAligner"]
