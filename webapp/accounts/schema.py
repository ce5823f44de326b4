"""How the OpenAPI schema describes the API token (registered when the accounts app loads)."""

from drf_spectacular.extensions import OpenApiAuthenticationExtension


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
