"""Forms of the team page, the invitation link and the new-password link."""

from __future__ import annotations

from django import forms
from django.contrib.auth import password_validation
from django.contrib.auth.forms import AuthenticationForm, UsernameField
from django.core.exceptions import ValidationError

from webapp.accounts.models import Role, User
from webapp.patients.models import Patient

ROLE_WORDS = [
    (Role.THERAPIST, "Therapist"),
    (Role.CLINIC_ADMIN, "Clinic admin (manages accounts, sees the audit log)"),
    (Role.PATIENT, "Patient (sees only their own recordings)"),
]


class InviteForm(forms.Form):
    role = forms.ChoiceField(choices=ROLE_WORDS, label="Invite a")
    patient = forms.ModelChoiceField(
        queryset=Patient.objects.none(),
        required=False,
        label="Patient",
        empty_label="— choose the patient (for a patient's login) —",
    )
    email = forms.EmailField(
        required=False,
        label="E-mail address (optional)",
        help_text="We send the link there too. Without an address, pass the link on yourself.",
    )

    def __init__(self, *args, clinic_id: int, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        patients = Patient.objects.filter(clinic_id=clinic_id, user__isnull=True)
        self.fields["patient"].queryset = patients.order_by("display_name")

    def clean(self):
        data = super().clean()
        if data.get("role") == Role.PATIENT and not data.get("patient"):
            self.add_error("patient", "Choose the patient this login is for.")
        if data.get("role") != Role.PATIENT:
            data["patient"] = None
        return data


class PatientInviteForm(forms.Form):
    email = InviteForm.base_fields["email"]


class NewPasswordForm(forms.Form):
    """Two matching passwords that pass the site's password rules."""

    password1 = forms.CharField(
        label="Password",
        strip=False,
        widget=forms.PasswordInput(attrs={"autocomplete": "new-password"}),
        help_text=password_validation.password_validators_help_text_html(),
    )
    password2 = forms.CharField(
        label="The same password again",
        strip=False,
        widget=forms.PasswordInput(attrs={"autocomplete": "new-password"}),
    )

    def user_for_checks(self) -> User:
        return User()

    def clean(self):
        data = super().clean()
        first, second = data.get("password1"), data.get("password2")
        if first and second and first != second:
            self.add_error("password2", "The two passwords differ.")
        elif first:
            try:
                password_validation.validate_password(first, self.user_for_checks())
            except forms.ValidationError as error:
                self.add_error("password1", error)
        return data


class AcceptInvitationForm(NewPasswordForm):
    username = UsernameField(
        max_length=150,
        help_text="Letters, digits and @ . + - _ only. You log in with it.",
        widget=forms.TextInput(attrs={"autocomplete": "username", "autofocus": True}),
    )
    field_order = ["username", "password1", "password2"]

    def clean_username(self) -> str:
        username = self.cleaned_data["username"]
        User.username_validator(username)
        if User.objects.filter(username__iexact=username).exists():
            raise forms.ValidationError("This username is taken: choose another.")
        return username

    def user_for_checks(self) -> User:
        return User(username=self.cleaned_data.get("username", ""))


class LoginForm(AuthenticationForm):
    """The login form; a deactivated account with its right password is told it is
    deactivated, not that the username and password didn't match (which sends people to
    retype a password that is right)."""

    DEACTIVATED = (
        "This account has been deactivated. Ask your clinic to reactivate it if you still need it."
    )

    deactivated = False

    def clean(self):
        try:
            return super().clean()
        except ValidationError as error:
            if getattr(error, "code", None) == "invalid_login" and self._deactivated():
                self.deactivated = True  # the page says so instead of "didn't match"
                raise ValidationError(self.DEACTIVATED, code="inactive") from error
            raise

    def _deactivated(self) -> bool:
        username = self.cleaned_data.get("username") or ""
        password = self.cleaned_data.get("password") or ""
        user = User.objects.filter(username=username, is_active=False).first()
        return user is not None and user.check_password(password)
