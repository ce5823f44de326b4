"""The OpenAPI schema of an analysis result, generated from the result dataclasses (one source).

`result_components` walks `AnalysisSummary` and every dataclass its fields hold (dataclass fields
and their type hints), with the differences each ``to_json`` declares in
`analysis.pipeline.results.JSON_SHAPES`, into one closed component per class
(``additionalProperties: false``, every key written always required): a key added to or dropped
from a result's JSON without its class saying so makes the API's answers fail their own schema.
drf-spectacular adds the components through `add_result_components` (a postprocessing hook) and
the serializers point at them with `RESULT_FIELD`.
"""

from __future__ import annotations

import copy
import dataclasses
import types
import typing
from collections.abc import Mapping, Sequence
from typing import Any

from analysis.pipeline.results import JSON_SHAPES, AnalysisSummary, JsonShape

Schema = dict[str, Any]
ROOT_NAME = "AnalysisResult"
REF_PREFIX = "#/components/schemas/"
SCALARS: dict[Any, Schema] = {
    bool: {"type": "boolean"},  # before int: a bool is an int to Python
    int: {"type": "integer"},
    float: {"type": "number"},
    str: {"type": "string"},
}


# OpenAPI 3.0.3: `nullable` only widens a `type` beside it, so {"allOf": [{"$ref": X}],
# "nullable": true} (drf-spectacular's way) still refuses null, X's type being object. A value
# that may be null is written {"anyOf": [{"$ref": X}, Null]} instead (`nullable_ref`), Null
# allowing null only (its `type` is there for `nullable` to widen; no string is in its enum).
NULL_NAME = "Null"
NULL_COMPONENT: Schema = {
    "type": "string",
    "description": "No value: JSON null.",
    "nullable": True,
    "enum": [None],
}


def nullable_ref(ref: Schema) -> Schema:
    return {"anyOf": [ref, {"$ref": REF_PREFIX + NULL_NAME}]}


def component_name(cls: type) -> str:
    """AnalysisSummary is the result itself; the others are named under it (no clash with the
    API's own serializers, such as its `Guidance` or `AngleRange`)."""
    return ROOT_NAME if cls is AnalysisSummary else ROOT_NAME + cls.__name__


def result_components() -> dict[str, Schema]:
    """Every component of the result, by name; the root is `ROOT_NAME`."""
    components: dict[str, Schema] = {NULL_NAME: dict(NULL_COMPONENT)}
    _add_class(AnalysisSummary, components)
    return components


def class_component(cls: type) -> Schema:
    """The generated component of one result dataclass (the components it refers to are among
    `result_components`, which the schema always holds)."""
    components: dict[str, Schema] = {}
    return components[_add_class(cls, components)]


def _add_class(cls: type, components: dict[str, Schema]) -> str:
    name = component_name(cls)
    if name in components:
        return name
    components[name] = {}  # placeholder: a class that holds itself stops here
    shape = JSON_SHAPES.get(cls, JsonShape())
    hints = typing.get_type_hints(cls)
    written = {
        f.name: hints[f.name] for f in dataclasses.fields(cls) if f.name not in shape.left_out
    }
    written.update(shape.written_as)
    written.update(shape.added)
    properties = {key: _schema_of(hint, components) for key, hint in written.items()}
    if "score" in properties:  # the interface contract: `score` is nullable wherever carried
        properties["score"] = {**properties["score"], "nullable": True}
    components[name] = {
        "type": "object",
        "description": _first_line(cls.__doc__),
        "properties": properties,
        "required": [key for key in written if key not in shape.optional],
        "additionalProperties": False,
    }
    return name


def _first_line(doc: str | None) -> str:
    return " ".join((doc or "").strip().split("\n\n")[0].split())


def _schema_of(hint: Any, components: dict[str, Schema]) -> Schema:
    """The OpenAPI 3.0 schema of one type hint."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        return _optional_schema(hint, components)
    if hint in SCALARS:
        return dict(SCALARS[hint])
    if dataclasses.is_dataclass(hint) and isinstance(hint, type):
        return {"$ref": REF_PREFIX + _add_class(hint, components)}
    if origin is tuple:
        return _tuple_schema(args, components)
    if origin in (list, Sequence) or origin is typing.Sequence:
        return {"type": "array", "items": _schema_of(args[0], components)}
    if origin in (dict, Mapping) or origin is typing.Mapping:
        key, value = args
        if key is not str:
            raise TypeError(f"JSON objects have string keys: {hint}")
        return {"type": "object", "additionalProperties": _schema_of(value, components)}
    raise TypeError(f"no JSON schema for {hint!r}")


def _optional_schema(hint: Any, components: dict[str, Schema]) -> Schema:
    """`X | None`: X's schema, null allowed."""
    present = [a for a in typing.get_args(hint) if a is not type(None)]
    if len(present) != 1:
        raise TypeError(f"only `X | None` unions are described: {hint}")
    inner = _schema_of(present[0], components)
    if "$ref" in inner:  # OpenAPI 3.0: `nullable` widens only a `type` beside it
        return nullable_ref(inner)
    return {**inner, "nullable": True}


def _tuple_schema(args: tuple[Any, ...], components: dict[str, Schema]) -> Schema:
    if len(args) == 2 and args[1] is Ellipsis:
        return {"type": "array", "items": _schema_of(args[0], components)}
    items = [_schema_of(a, components) for a in args]
    if any(item != items[0] for item in items):
        raise TypeError(f"fixed tuples of one item type only: {args}")
    return {"type": "array", "items": items[0], "minItems": len(items), "maxItems": len(items)}


# The serializers' `result` field: the typed result's JSON, null until the run succeeded.
RESULT_FIELD: Schema = nullable_ref({"$ref": REF_PREFIX + ROOT_NAME})


def add_result_components(result: Schema, generator=None, request=None, public=None) -> Schema:
    """drf-spectacular postprocessing hook (SPECTACULAR_SETTINGS["POSTPROCESSING_HOOKS"])."""
    schemas = result.setdefault("components", {}).setdefault("schemas", {})
    schemas.update(result_components())
    return result


def json_schema() -> Schema:
    """The result's schema in plain JSON Schema (for jsonschema in the tests): OpenAPI's
    ``nullable`` becomes a null alternative, the components become ``$defs``."""
    components = {name: _plain(s) for name, s in result_components().items()}
    return {"$ref": "#/$defs/" + ROOT_NAME, "$defs": components}


def _plain(node: Any) -> Any:
    if isinstance(node, list):
        return [_plain(item) for item in node]
    if not isinstance(node, dict):
        return node
    out = {key: _plain(value) for key, value in node.items() if key != "nullable"}
    if isinstance(out.get("$ref"), str):
        out["$ref"] = out["$ref"].replace(REF_PREFIX, "#/$defs/")
    if node.get("nullable"):
        return {"anyOf": [out, {"type": "null"}]}
    return copy.deepcopy(out)
