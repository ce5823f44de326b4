"""Periodic landmark sequence analysis (GA^K and the string-alignment baselines): drop the members
of a landmark sequence that break the exercise's cycle.

Pipeline: `clean` is called on the identified key poses before repetitions are cut from them.
"""

from analysis.periodic.sequence import clean

__all__ = ["clean"]
