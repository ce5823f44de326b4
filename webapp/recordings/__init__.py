"""Uploaded recordings and their analysis runs."""
