"""The audit log in Django's admin: readable, never added to, changed or deleted."""

from django.contrib import admin

from webapp.audit.models import AuditEvent


@admin.register(AuditEvent)
class AuditEventAdmin(admin.ModelAdmin):
    list_display = ("at", "clinic", "username", "action", "object_type", "patient_id", "ip_address")
    list_filter = ("clinic", "action", "object_type")
    search_fields = ("username", "object_id", "path")
    date_hierarchy = "at"

    def has_add_permission(self, request) -> bool:
        return False

    def has_change_permission(self, request, obj=None) -> bool:
        return False

    def has_delete_permission(self, request, obj=None) -> bool:
        return False
