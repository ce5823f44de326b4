"""Clinics, users and their roles."""
