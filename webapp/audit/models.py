"""Audit events: who did what to which patient's data, when and from where.

The application only ever inserts: saving an existing event or deleting one raises.
"""

from __future__ import annotations

from django.conf import settings
from django.db import models

from webapp.accounts.models import Clinic
from webapp.audit.words import kind_words


class AppendOnlyError(RuntimeError):
    pass


class AuditEventQuerySet(models.QuerySet):
    """Bulk changes bypass `Model.save`/`delete`: refuse them too."""

    def update(self, **kwargs):
        raise AppendOnlyError("Audit events cannot be changed.")

    def delete(self):
        raise AppendOnlyError("Audit events cannot be deleted.")


class AuditEvent(models.Model):
    class Action(models.TextChoices):
        READ = "read", "Read"
        CREATE = "create", "Create"
        UPDATE = "update", "Update"
        DELETE = "delete", "Delete"
        EXPORT = "export", "Export"
        ARCHIVE = "archive", "Archive"
        RESTORE = "restore", "Bring back"

    clinic = models.ForeignKey(Clinic, on_delete=models.PROTECT, related_name="+")
    user = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, related_name="+"
    )
    username = models.CharField(max_length=150)
    action = models.CharField(max_length=10, choices=Action.choices)
    object_type = models.CharField(max_length=50)
    object_id = models.CharField(max_length=64)
    patient_id = models.UUIDField(null=True, db_index=True)
    path = models.CharField(max_length=2000)  # the full path and query: exactly what was asked
    ip_address = models.GenericIPAddressField(null=True)
    at = models.DateTimeField(auto_now_add=True, db_index=True)
    # How the request came in: "web" (session) or "token <prefix>" (API token).
    via = models.CharField(max_length=40, blank=True)
    # What was seen or changed, in words, as it was at the time (`webapp.audit.words`).
    description = models.CharField(max_length=300, blank=True)

    objects = AuditEventQuerySet.as_manager()

    class Meta:
        ordering = ["-at"]
        indexes = [models.Index(fields=["clinic", "-at"])]

    @property
    def what(self) -> str:
        """The event's object in words (events written before `description` name its kind)."""
        return self.description or kind_words(self.object_type)

    def save(self, *args, **kwargs):
        if self.pk is not None or not self._state.adding:
            raise AppendOnlyError("Audit events cannot be changed.")
        super().save(*args, **kwargs)

    def delete(self, *args, **kwargs):
        raise AppendOnlyError("Audit events cannot be deleted.")
