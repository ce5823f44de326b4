"""OpenAPI for the API views: the error answers every operation can give are documented too.

drf-spectacular documents only the success answer. Clients (and schemathesis) need to know that a
missing or revoked token answers 401, a forbidden action 403, another clinic's or an unknown
object 404 and bad input 400, each with a JSON body that says why.
"""

from __future__ import annotations

from drf_spectacular.openapi import AutoSchema

ERROR_BODY = {
    "type": "object",
    "description": "Why the request failed: {'detail': message} or {field: [messages]}.",
    "additionalProperties": True,
}
ALWAYS = ("401", "403")


class ApiSchema(AutoSchema):
    def _get_response_bodies(self, direction="response"):
        bodies = super()._get_response_bodies(direction)
        if direction != "response":
            return bodies
        for code in self.error_codes():
            if code not in bodies:
                bodies[code] = self._get_response_for_code(dict(ERROR_BODY), code)
        return bodies

    def error_codes(self) -> list[str]:
        codes = list(ALWAYS)
        if self.method in ("POST", "PUT", "PATCH") or self.view_has_query_parameters():
            codes.append("400")
        if "{" in self.path:  # an unknown object, or another clinic's
            codes.append("404")
        return codes

    def view_has_query_parameters(self) -> bool:
        return any(p.get("in") == "query" for p in self._get_parameters())
