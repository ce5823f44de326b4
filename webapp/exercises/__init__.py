"""Exercises, their tutor recordings and their versioned models."""
