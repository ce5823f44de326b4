"""OpenAPI for the API views: every object closed, and the error answers documented too.

Every object a serializer describes is closed (``additionalProperties: false``): a serializer
writes exactly its declared fields, so the schema says so, and a key a view adds beside its
serializer fails the validating hook every API test response goes through
(tests/webapp/conftest.py). The analysis result's components are generated from its dataclasses
(`webapp.api.result_schema`).

drf-spectacular documents only the success answer. Clients (and schemathesis) need to know that a
missing or revoked token answers 401, a forbidden action 403, another clinic's or an unknown
object 404 and bad input 400, each with a JSON body that says why (`ERROR_COMPONENTS`: DRF's
``{"detail": message}`` or ``{field: messages}``, which is a map from a field's name to its
messages, never an object of any shape).
"""

from __future__ import annotations

import functools
from typing import Any

from drf_spectacular.openapi import AutoSchema
from rest_framework.pagination import BasePagination

from webapp.api.result_schema import (
    NULL_COMPONENT,
    NULL_NAME,
    REF_PREFIX,
    Schema,
    class_component,
    nullable_ref,
)

REF = REF_PREFIX
ERROR_NAME = "Error"
# DRF's and Django forms' messages: a message, a list of messages (strings, or Django form errors'
# {"message", "code"}), or the messages of a nested serializer's fields by name.
ERROR_COMPONENTS: dict[str, Schema] = {
    ERROR_NAME: {
        "type": "object",
        "description": "Why the request failed: {'detail': message} or {field: messages}.",
        "additionalProperties": {"$ref": REF + "ErrorMessages"},
    },
    "ErrorMessages": {
        "description": "A message, a list of messages, or a nested field's messages by name.",
        "anyOf": [
            {"type": "string"},
            {"type": "array", "items": {"$ref": REF + "ErrorMessage"}},
            {"type": "object", "additionalProperties": {"$ref": REF + "ErrorMessages"}},
        ],
    },
    "ErrorMessage": {
        "anyOf": [
            {"type": "string"},
            {
                "type": "object",
                "description": "A Django form error.",
                "properties": {"message": {"type": "string"}, "code": {"type": "string"}},
                "required": ["message", "code"],
                "additionalProperties": False,
            },
        ],
    },
}
ERROR_BODY: Schema = {"$ref": REF + ERROR_NAME}
ALWAYS = ("401", "403")


class ApiSchema(AutoSchema):
    def _map_basic_serializer(self, serializer, direction):
        schema = super()._map_basic_serializer(serializer, direction)
        schema["additionalProperties"] = False  # a serializer writes exactly its fields
        result_class = getattr(getattr(serializer, "Meta", None), "result_class", None)
        if result_class is not None:
            schema = with_result_class(schema, result_class)
        return schema

    def _get_paginator(self):
        paginator = super()._get_paginator()
        return closed_pages(type(paginator))() if paginator else None

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
        if "{" in self.path or self.method in ("POST", "PUT", "PATCH"):
            codes.append("404")  # an unknown object (in the path or the body), another clinic's
        return codes

    def view_has_query_parameters(self) -> bool:
        return any(p.get("in") == "query" for p in self._get_parameters())


def with_result_class(schema: Schema, result_class: type) -> Schema:
    """A serializer that writes a result dataclass's JSON plus keys of its own
    (``Meta.result_class``): the dataclass's keys and types (generated, `result_class_component`)
    with the serializer's fields beside them; a key both name is the serializer's."""
    generated = class_component(result_class)
    properties = {**generated["properties"], **schema.get("properties", {})}
    required = [*generated["required"], *schema.get("required", [])]
    return {
        **schema,
        "properties": properties,
        "required": list(dict.fromkeys(required)),
        "additionalProperties": False,
    }


@functools.cache
def closed_pages(pagination: type[BasePagination]) -> type[BasePagination]:
    """The pagination class, its page (count, next, previous, results) described as closed."""

    class Closed(pagination):
        def get_paginated_response_schema(self, schema: Schema) -> Schema:
            page = super().get_paginated_response_schema(schema)
            return {**page, "additionalProperties": False}

    return Closed


def finish_schema(result: Schema, generator=None, request=None, public=None) -> Schema:
    """drf-spectacular postprocessing hook (SPECTACULAR_SETTINGS["POSTPROCESSING_HOOKS"], the
    last one): the error bodies' components; every nullable reference written so that null is
    allowed (`nullable_ref`); and ``score`` nullable wherever it is carried (the interface
    contract: a recording that does not fit its exercise has no score)."""
    schemas = result.setdefault("components", {}).setdefault("schemas", {})
    schemas.update(ERROR_COMPONENTS)
    schemas[NULL_NAME] = dict(NULL_COMPONENT)
    _null_refs(result)
    for schema in schemas.values():
        score = schema.get("properties", {}).get("score")
        if score is not None and "type" in score:
            score["nullable"] = True
    return result


def _null_refs(node: Any) -> None:
    """Rewrite {"allOf": [one $ref], "nullable": true, ...} in place as `nullable_ref`."""
    if isinstance(node, list):
        for item in node:
            _null_refs(item)
        return
    if not isinstance(node, dict):
        return
    parts = node.get("allOf")
    one_ref = isinstance(parts, list) and len(parts) == 1 and set(parts[0]) == {"$ref"}
    if node.get("nullable") is True and one_ref:
        del node["allOf"], node["nullable"]
        node.update(nullable_ref(parts[0]))
    for value in node.values():
        _null_refs(value)


def open_objects(node: Any, where: str = "") -> list[str]:
    """Where `node` (a schema document or part of it) describes an object that takes keys it does
    not name: ``additionalProperties`` left out, ``true`` or ``{}``. A map (an object whose keys
    are names, such as a joint's angle ranges by angle) gives its values' schema instead."""
    found: list[str] = []
    if isinstance(node, list):
        for index, item in enumerate(node):
            found += open_objects(item, f"{where}[{index}]")
        return found
    if not isinstance(node, dict):
        return found
    if node.get("type") == "object" or "properties" in node:
        extra = node.get("additionalProperties")
        if extra is None or extra is True or extra == {}:
            found.append(where or "/")
    for key, value in node.items():
        found += open_objects(value, f"{where}/{key}")
    return found
