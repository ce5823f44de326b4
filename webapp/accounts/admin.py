from django.contrib import admin
from django.contrib.auth.admin import UserAdmin

from webapp.accounts.models import Clinic, User


@admin.register(User)
class ClinicUserAdmin(UserAdmin):
    fieldsets = (*UserAdmin.fieldsets, ("Clinic", {"fields": ("clinic", "role")}))
    list_display = ("username", "clinic", "role", "is_active")
    list_filter = ("clinic", "role", "is_active")


admin.site.register(Clinic)
