"""Append-only log of every read and write of patient data."""
