"""What one graph file may say: the JSON schema of its keys, the forms of its names, signals
and plugs, and the check of a file's plain data against them (with a readable message)."""

from __future__ import annotations

import re
from typing import Any

import jsonschema

from dgraph.errors import GraphFileError
from dgraph.files.source import Document

NAME_RE = r"^[A-Za-z_][A-Za-z0-9_\-]*$"
SIGNAL_RE = r"^[A-Za-z_][A-Za-z0-9_\-]*\.[A-Za-z_][A-Za-z0-9_]*$"
PLUG_PATTERN = r"^\s*\S+\s*->\s*\S+\s*$"
UNPLUG_PATTERN = r"^\s*(\S+\s*->\s*)?\S+\s*$"
PLUG_RE = re.compile(r"^\s*(\S+)\s*->\s*(\S+)\s*$")

_SIGNALS = {"type": "array", "items": {"type": "string", "pattern": SIGNAL_RE}}
_SETTINGS = {"type": "object", "propertyNames": {"pattern": SIGNAL_RE}}
SCHEMA: dict[str, Any] = {
    "type": "object",
    "additionalProperties": False,
    "properties": {
        "name": {"type": "string", "minLength": 1},
        "dt": {"type": "number", "exclusiveMinimum": 0},
        "duration": {"type": "number", "minimum": 0},
        "robot": {"type": "string", "minLength": 1},
        "entities": {
            "type": "object",
            "propertyNames": {"pattern": NAME_RE},
            "additionalProperties": {
                "type": "object",
                "additionalProperties": False,
                "required": ["type"],
                "properties": {"type": {"type": "string"}, "params": {"type": "object"}},
            },
        },
        "plugs": {"type": "array", "items": {"type": "string", "pattern": PLUG_PATTERN}},
        "set": _SETTINGS,
        "record": _SIGNALS,
        "extends": {"anyOf": [{"type": "string", "minLength": 1},
                              {"type": "array", "minItems": 1, "items": {"type": "string", "minLength": 1}}]},
        "remove": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "entities": {"type": "array", "items": {"type": "string", "pattern": NAME_RE}},
                "plugs": {"type": "array", "items": {"type": "string", "pattern": UNPLUG_PATTERN}},
                "set": _SIGNALS,
                "record": _SIGNALS,
            },
        },
        "overrides": _SETTINGS,
    },
    "if": {"not": {"required": ["extends"]}},
    "then": {"required": ["entities"]},
    "dependentRequired": {"remove": ["extends"], "overrides": ["extends"]},
}
_PATTERNS = {SIGNAL_RE: "'entity.signal'", PLUG_PATTERN: "'entity.output -> entity.input'",
             UNPLUG_PATTERN: "'entity.output -> entity.input' or 'entity.input'", NAME_RE: "an entity name"}


def validate(data: Any, doc: Document) -> dict[str, Any]:
    """``data``, the plain data of the file ``doc``, if it is a graph file; else the error at
    the offending key."""
    if not isinstance(data, dict):
        raise GraphFileError("a graph file must be a mapping with an 'entities' key", file=doc.file, line=1)
    errors = sorted(jsonschema.Draft202012Validator(SCHEMA).iter_errors(data), key=lambda e: list(e.absolute_path))
    if errors:
        message, path = _schema_message(jsonschema.exceptions.best_match(errors))
        raise doc.error(message, path)
    return data


def _schema_message(err: jsonschema.ValidationError) -> tuple[str, tuple[Any, ...]]:
    """A readable message for a schema violation and the path of the offending key or value."""
    path = tuple(err.absolute_path)
    if err.validator == "additionalProperties":
        allowed = err.schema.get("properties", {})
        extra = [k for k in err.instance if k not in allowed]
        return f"unknown key {extra[0]!r} (allowed: {', '.join(allowed)})", (*path, extra[0])
    if err.validator == "dependentRequired":
        key = next(k for k in SCHEMA["dependentRequired"] if k in err.instance)
        return f"{key!r} is for a file that extends another (it has no 'extends')", (*path, key)
    if "propertyNames" in err.schema_path:  # a key itself is wrong: point at it
        bad = err.instance
        if path == ("entities",):
            return f"invalid entity name {bad!r}: use letters, digits, '_' or '-', starting with a letter", (*path, bad)
        return f"{bad!r} must read 'entity.signal'", (*path, bad)
    if err.validator == "pattern":
        what = "plug " if err.schema["pattern"] in (PLUG_PATTERN, UNPLUG_PATTERN) else ""
        return f"{what}{err.instance!r} must read {_PATTERNS[err.schema['pattern']]}", path
    return err.message, path
