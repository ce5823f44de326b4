"""Every answer the test suite's client receives from `/api/v1/` is checked against the served
OpenAPI schema (as zulip validates every test response against its OpenAPI document): its status
code must be documented for the operation, its content type too, and a JSON body must fit the
documented schema, whose objects are all closed (`webapp.api.schema`). tests/webapp/conftest.py
installs `check_response` on Django's test client (and so on DRF's APIClient, built on it).
"""

from __future__ import annotations

import functools
import json
import re
from typing import Any

from drf_spectacular.generators import SchemaGenerator
from openapi_schema_validator import OAS30ReadValidator, oas30_format_checker

API_PREFIX = "/api/v1/"
JSON_TYPES = ("application/json", "application/fhir+json")


class SchemaMismatchError(AssertionError):
    """An API answer the served schema does not describe."""


@functools.cache
def served_schema() -> dict[str, Any]:
    """The document `/api/schema/` serves (the same generator, as JSON)."""
    spec = SchemaGenerator().get_schema(request=None, public=True)
    return json.loads(json.dumps(spec, default=str))


SEGMENTS = {"uuid": "[0-9a-fA-F]{8}(-[0-9a-fA-F]{4}){3}-[0-9a-fA-F]{12}", "integer": "[0-9]+"}


def segment(template: str, name: str) -> str:
    """The pattern of path parameter `name` as its schema types it (Django's path converters
    answer a value of another form with their own 404, which no API view gives)."""
    for operation in served_schema()["paths"][template].values():
        for parameter in operation.get("parameters", []):
            if parameter["in"] == "path" and parameter["name"] == name:
                schema = parameter.get("schema", {})
                return SEGMENTS.get(schema.get("format") or schema.get("type"), "[^/]+")
    return "[^/]+"


def _typed(template: str, match: re.Match[str]) -> str:
    return segment(template, match.group(1))


@functools.cache
def paths() -> list[tuple[re.Pattern[str], str]]:
    """Each documented path as a pattern, with its template."""
    found = []
    for template in served_schema()["paths"]:
        pattern = re.escape(template).replace(r"\{", "{").replace(r"\}", "}")
        pattern = re.sub(r"{([^}/]+)}", functools.partial(_typed, template), pattern)
        found.append((re.compile(pattern + "$"), template))
    return found


def template_of(path: str) -> str | None:
    return next((template for pattern, template in paths() if pattern.match(path)), None)


@functools.cache
def validator(method: str, template: str, code: str, media: str) -> OAS30ReadValidator:
    spec = served_schema()
    schema = spec["paths"][template][method]["responses"][code]["content"][media]["schema"]
    # The components beside the answer's schema: its $refs resolve inside this one document.
    return OAS30ReadValidator(
        {**schema, "components": spec["components"]}, format_checker=oas30_format_checker
    )


def asked_for(response) -> str:
    request = getattr(response, "wsgi_request", None)
    return request.META.get("HTTP_ACCEPT", "") if request is not None else ""


def check_error_body(where: str, media: str, body: bytes) -> None:
    if media != "application/json":
        raise SchemaMismatchError(f"{where}: a {media!r} body where the schema documents none")
    errors = list(error_validator().iter_errors(json.loads(body)))
    if errors:
        raise SchemaMismatchError(f"{where}: not an error body: {errors[0].message[:300]}")


@functools.cache
def error_validator() -> OAS30ReadValidator:
    spec = served_schema()
    error = {"$ref": "#/components/schemas/Error", "components": spec["components"]}
    return OAS30ReadValidator(error, format_checker=oas30_format_checker)


def check_response(method: str, path: str, response) -> None:
    """Raise `SchemaMismatchError` when `response` to ``method path`` is not as documented."""
    if not path.startswith(API_PREFIX):
        return
    template = template_of(path)
    operation = served_schema()["paths"][template].get(method.lower()) if template else None
    if operation is None:
        return  # an undocumented method or path answers 404/405 from Django or DRF itself
    where = f"{method} {path} -> {response.status_code}"
    documented = operation["responses"].get(str(response.status_code))
    if documented is None:
        raise SchemaMismatchError(
            f"{where}: status not documented ({sorted(operation['responses'])})"
        )
    media = response.get("Content-Type", "").split(";")[0].strip()
    if media == "text/html" and "text/html" in asked_for(response):
        return  # DRF's browsable API: any answer as a page for a browser, not the API's JSON
    content = documented.get("content", {})
    if not content:  # a refusal described in words only: its body must be an error body
        if response.content:
            check_error_body(where, media, response.content)
        return
    if media not in content:
        raise SchemaMismatchError(
            f"{where}: content type {media!r} not documented ({list(content)})"
        )
    if media not in JSON_TYPES:
        return
    body = json.loads(response.content)
    errors = sorted(
        validator(method.lower(), template, str(response.status_code), media).iter_errors(body),
        key=lambda e: list(e.absolute_path),
    )
    if errors:
        lines = [f"  {'/'.join(map(str, e.absolute_path))}: {e.message[:300]}" for e in errors[:8]]
        told = "\n".join(lines)
        raise SchemaMismatchError(f"{where}: the body does not fit the served schema\n{told}")
