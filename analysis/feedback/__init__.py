"""Feedback in words: the assessment grammar (parser, printer), its matching, and the sentences.

Pipeline: the assessed key poses go through the exercise's grammar to give the feedback list.
The exercise form checks a grammar with `check_names` (no body part or key-pose type it lacks).
"""

from analysis.feedback.grammar import GrammarError
from analysis.feedback.known_names import check_names
from analysis.feedback.sentences import Comment, Grammar, LandmarkAssessment, default_grammar

__all__ = [
    "Comment",
    "Grammar",
    "GrammarError",
    "LandmarkAssessment",
    "check_names",
    "default_grammar",
]
