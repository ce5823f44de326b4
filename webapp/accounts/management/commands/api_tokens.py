"""Issue, list and revoke API tokens from the command line.

manage.py api_tokens issue USERNAME --name "billing system" [--days 365]
manage.py api_tokens list [--clinic NAME]
manage.py api_tokens revoke TOKEN_ID_OR_KEY_PREFIX
"""

from __future__ import annotations

from django.core.management.base import BaseCommand, CommandError
from django.db.models import Q

from webapp.accounts.models import ApiToken, User
from webapp.accounts.tokens import issue_token, revoke_token


class Command(BaseCommand):
    help = "Issue, list and revoke clinic-scoped API tokens."

    def add_arguments(self, parser) -> None:
        actions = parser.add_subparsers(dest="action", required=True)
        issue = actions.add_parser("issue", help="issue a token; prints the key once")
        issue.add_argument("username")
        issue.add_argument("--name", required=True)
        issue.add_argument("--days", type=int, default=None, help="expiry (default: none)")
        listing = actions.add_parser("list", help="list tokens (never their keys)")
        listing.add_argument("--clinic", default=None)
        revoke = actions.add_parser("revoke", help="revoke a token by id or key prefix")
        revoke.add_argument("token")

    def handle(self, *args, action: str, **options) -> None:
        getattr(self, f"do_{action}")(**options)

    def do_issue(self, username: str, name: str, days: int | None, **_) -> None:
        user = User.objects.filter(username=username).first()
        if user is None or user.clinic_id is None:
            raise CommandError(f"No clinic member called {username!r}.")
        token, key = issue_token(user, name, days=days)
        self.stdout.write(f"{token.pk} {key}")

    def do_list(self, clinic: str | None, **_) -> None:
        tokens = ApiToken.objects.select_related("user", "clinic")
        if clinic:
            tokens = tokens.filter(clinic__name=clinic)
        for token in tokens:
            state = "revoked" if token.revoked_at else "active" if token.is_active else "expired"
            self.stdout.write(
                f"{token.pk} {token.prefix} {token.clinic} {token.user} {token.name!r} {state}"
            )

    def do_revoke(self, token: str, **_) -> None:
        query = Q(prefix=token)
        if len(token) == 36:
            query |= Q(pk=token)
        matches = list(ApiToken.objects.filter(query)[:2])
        if len(matches) != 1:
            raise CommandError(f"{len(matches)} tokens match {token!r}; give the token id.")
        revoke_token(matches[0])
        self.stdout.write(f"revoked {matches[0].pk}")
