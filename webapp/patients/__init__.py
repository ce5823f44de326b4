"""Patients, their prescriptions and performance levels."""
