from django.contrib.auth import views as auth_views
from django.urls import path, reverse_lazy

from webapp.accounts import link_views, team_views, token_views, two_factor
from webapp.accounts.forms import LoginForm

app_name = "accounts"

urlpatterns = [
    path(
        "login/",
        auth_views.LoginView.as_view(
            template_name="accounts/login.html",
            redirect_authenticated_user=True,
            authentication_form=LoginForm,
        ),
        name="login",
    ),
    path("logout/", auth_views.LogoutView.as_view(), name="logout"),
    path(
        "password/change/",
        auth_views.PasswordChangeView.as_view(
            success_url=reverse_lazy("accounts:password-changed")
        ),
        name="password-change",
    ),
    path("password/changed/", auth_views.PasswordChangeDoneView.as_view(), name="password-changed"),
    path(
        "password/reset/",
        auth_views.PasswordResetView.as_view(
            success_url=reverse_lazy("accounts:password-reset-sent"),
            email_template_name="registration/reset_email.txt",
        ),
        name="password-reset",
    ),
    path(
        "password/reset/sent/",
        auth_views.PasswordResetDoneView.as_view(),
        name="password-reset-sent",
    ),
    path(
        "password/reset/<uidb64>/<token>/",
        auth_views.PasswordResetConfirmView.as_view(
            success_url=reverse_lazy("accounts:password-reset-complete")
        ),
        name="password-reset-confirm",
    ),
    path(
        "password/reset/done/",
        auth_views.PasswordResetCompleteView.as_view(),
        name="password-reset-complete",
    ),
    path("2fa/setup/", two_factor.setup, name="2fa-setup"),
    path("2fa/verify/", two_factor.verify, name="2fa-verify"),
    path("tokens/", token_views.token_list, name="tokens"),
    path("tokens/<uuid:pk>/revoke/", token_views.token_revoke, name="token-revoke"),
    path("team/", team_views.team, name="team"),
    path(
        "team/<uuid:pk>/deactivate/",
        team_views.set_active,
        {"active": False},
        name="team-deactivate",
    ),
    path(
        "team/<uuid:pk>/reactivate/",
        team_views.set_active,
        {"active": True},
        name="team-reactivate",
    ),
    path("team/<uuid:pk>/password-link/", team_views.password_link, name="team-password-link"),
    path("team/links/<uuid:pk>/withdraw/", team_views.withdraw_link, name="team-withdraw-link"),
    path("invite/patient/<uuid:pk>/", team_views.invite_patient, name="invite-patient"),
    path("invitation/<str:token>/", link_views.accept_invitation, name="invitation"),
    path("new-password/<str:token>/", link_views.new_password, name="new-password"),
]
