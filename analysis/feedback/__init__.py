"""Feedback in words: the assessment grammar (parser, printer), its matching, and the sentences.

Pipeline: the assessed key poses go through the exercise's grammar to give the feedback list.
"""

from analysis.feedback.grammar import GrammarError
from analysis.feedback.sentences import Comment, Grammar, LandmarkAssessment, default_grammar

__all__ = ["Comment", "Grammar", "GrammarError", "LandmarkAssessment", "default_grammar"]
