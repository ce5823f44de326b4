"""Synchronisation with the tutor and affine adjustment of motions toward each other's key poses.

Pipeline: the last stage builds the four playback skeletons (patient, tutor, and each adjusted
toward the other by the patient's level).
"""

from analysis.adjustment.affine import Performance, demonstration_skeletons, gamma_vector

__all__ = ["Performance", "demonstration_skeletons", "gamma_vector"]
