"""How the OpenAPI schema describes the API token (registered when the accounts app loads): the
scheme, and the token endpoint's question (`PasswordForToken`) and answers (`TokenAnswer`, or why
not: a refusal, or 429 while django-axes keeps a username locked out)."""

from drf_spectacular.extensions import OpenApiAuthenticationExtension, OpenApiViewExtension
from drf_spectacular.utils import OpenApiResponse, extend_schema

from webapp.accounts.tokens import PasswordForToken, TokenAnswer
from webapp.api.schema import ERROR_BODY


class ClinicTokenScheme(OpenApiAuthenticationExtension):
    target_class = "webapp.accounts.authentication.ClinicTokenAuthentication"
    name = "tokenAuth"

    def get_security_definition(self, auto_schema):
        return {
            "type": "apiKey",
            "in": "header",
            "name": "Authorization",
            "description": 'Clinic-scoped token: "Token <key>" (POST /api/v1/auth/token/).',
        }


class ObtainTokenSchema(OpenApiViewExtension):
    """`ObtainToken` names its question as its serializer; what it answers is `TokenAnswer`."""

    target_class = "webapp.accounts.tokens.ObtainToken"

    def view_replacement(self):
        locked = OpenApiResponse(ERROR_BODY, description="Too many failed logins: locked a while.")

        @extend_schema(request=PasswordForToken, responses={200: TokenAnswer, 429: locked})
        class Described(self.target_class):
            pass

        return Described
