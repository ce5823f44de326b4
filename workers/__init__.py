"""Celery app and thin tasks: they take ids, load from the database and storage, call
`analysis`, and store the results."""

from workers.celery import app

__all__ = ["app"]
