from django.contrib import admin
from django.contrib.auth.admin import UserAdmin

from webapp.accounts.models import ApiToken, Clinic, User
from webapp.accounts.tokens import revoke_token


@admin.register(User)
class ClinicUserAdmin(UserAdmin):
    fieldsets = (*UserAdmin.fieldsets, ("Clinic", {"fields": ("clinic", "role")}))
    list_display = ("username", "clinic", "role", "is_active")
    list_filter = ("clinic", "role", "is_active")


admin.site.register(Clinic)


@admin.register(ApiToken)
class ApiTokenAdmin(admin.ModelAdmin):
    """Tokens are issued from the tokens page or `manage.py api_tokens`; here only revoked."""

    list_display = ("name", "prefix", "clinic", "user", "created_at", "last_used_at", "revoked_at")
    list_filter = ("clinic",)
    readonly_fields = [f.name for f in ApiToken._meta.fields]
    actions = ["revoke"]

    def has_add_permission(self, request) -> bool:
        return False

    @admin.action(description="Revoke the selected tokens")
    def revoke(self, request, queryset) -> None:
        for token in queryset:
            revoke_token(token)
