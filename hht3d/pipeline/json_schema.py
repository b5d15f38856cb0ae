"""A JSON Schema of pipeline files, generated from the operation and format registries.

Editors validate and complete pipeline YAML with it (VS Code's YAML
extension: a ``# yaml-language-server: $schema=...`` first line, or the
``yaml.schemas`` setting; see docs/guide/pipelines.md).  The package ships it as
``hht3d/data/pipeline.schema.json`` (:func:`hht3d.io.read.data_path`), written by
``hht3d schema --output hht3d/data/pipeline.schema.json``; a test fails when
the shipped file differs from :func:`pipeline_schema`.

The schema says what the types can say: the keys of every block, each
operation's parameters with their types, ranges, choices and defaults, the
gains, the output formats and their options.  What needs the pipeline as a
whole (references between steps, the kind a step makes, vertex counts,
writable outputs) is left to :class:`~hht3d.pipeline.validation.Validator`,
which ``hht3d validate`` runs.

Examples
--------
>>> from hht3d.pipeline.json_schema import pipeline_schema
>>> schema = pipeline_schema()
>>> schema["required"]
['version', 'inputs', 'steps', 'outputs']
>>> emd = next(rule["then"] for rule in schema["$defs"]["step"]["allOf"]
...            if rule["if"]["properties"]["op"]["const"] == "emd")
>>> emd["properties"]["params"]["properties"]["max_imfs"]
{'type': 'integer', 'description': 'at most this many IMFs', 'default': 10, 'minimum': 0, 'maximum': 64}
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable
from typing import Any

from ..apps.filters import GAINS
from ..output_formats import FORMATS
from .params import Param, record_params
from .plugins import operations
from .validation import EXECUTION, MAX_ID, VERSION, builtin_models

__all__ = ["pipeline_schema", "schema_text", "param_schema"]

_TYPES = {"int": "integer", "float": "number", "bool": "boolean", "str": "string", "ints": "array", "strs": "array"}


def param_schema(param: Param) -> dict:
    """The JSON Schema of one parameter's values."""
    nullable = param.default is None or param.nullable
    if param.kind == "choice":
        schema: dict[str, Any] = {"enum": [*param.choices, *([None] if nullable else [])]}
    elif param.kind == "gain":
        schema = {"$ref": "#/$defs/gain"}
    else:
        schema = {"type": [_TYPES[param.kind], "null"] if nullable else _TYPES[param.kind]}
    schema["description"] = param.doc
    if not param.required and _is_json(param.default):
        schema["default"] = param.default
    numbers = schema
    if param.kind == "ints":  # the range holds for each item
        numbers = schema["items"] = {"type": "integer"}
        schema["minItems"] = 1
    elif param.kind == "strs":
        schema["items"] = {"type": "string", "minLength": 1}
        schema["minItems"] = 1
    for bound, key in ((param.minimum, "minimum"), (param.maximum, "maximum")):
        if bound is not None:
            is_open = param.open_minimum if key == "minimum" else param.open_maximum
            numbers["exclusiveM" + key[1:] if is_open else key] = bound
    return schema


def _is_json(value: Any) -> bool:
    return value is None or isinstance(value, (bool, int, float, str))


def _object(params: Iterable[Any], *, description: str | None = None, extra: dict | None = None) -> dict:
    """An object of these parameters and no others (``extra``: more properties)."""
    schema = {
        "type": "object",
        **({"description": description} if description else {}),
        "properties": {**(extra or {}), **{p.name: param_schema(p) for p in params}},
        "additionalProperties": False,
    }
    required = [p.name for p in params if p.required]
    if required:
        schema["required"] = required
    return schema


def _gain_schema() -> dict:
    """One branch per gain kind of :data:`hht3d.apps.GAINS`, with its fields."""
    branches = []
    for kind, cls in GAINS.items():
        fields = dataclasses.fields(cls)
        properties: dict[str, Any] = {"kind": {"const": kind}}
        for f in fields:
            properties[f.name] = (
                {
                    "type": "array",
                    "items": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
                    "minItems": 1,
                }
                if f.name == "points"
                else {"type": "number"}
            )
        required = ["kind", *(f.name for f in fields if f.default is dataclasses.MISSING)]
        branches.append(
            {
                "type": "object",
                "description": (cls.__doc__ or kind).strip().splitlines()[0],
                "properties": properties,
                "required": required,
                "additionalProperties": False,
            }
        )
    return {"description": "a gain μ(ω) of the instantaneous frequency", "oneOf": branches}


def _step_schema() -> dict:
    """A step: its keys, then per op (``if op is X then params are X's``)."""
    reference = {"type": "string", "pattern": f"^[A-Za-z0-9_-]{{1,{MAX_ID}}}$"}
    return {
        "type": "object",
        "properties": {
            "id": {**reference, "description": "the step's name (default: the op)"},
            "op": {"enum": list(operations()), "description": "the operation (`hht3d ops` lists them)"},
            "from": {
                "description": "the step whose result feeds it, or {slot: step id}",
                "anyOf": [reference, {"type": "object", "additionalProperties": reference}],
            },
            "params": {"type": ["object", "null"]},
        },
        "required": ["op"],
        "additionalProperties": False,
        "allOf": [
            {
                "if": {"properties": {"op": {"const": op.name}}, "required": ["op"]},
                "then": {
                    "description": op.summary,
                    "properties": {"params": _object(op.params, description=op.summary)},
                },
            }
            for op in operations().values()
        ],
    }


def _output_schema() -> dict:
    """An output file: where from, where to, the format and the union of the formats' options."""
    options: dict[str, list[dict]] = {}
    for formats in FORMATS.values():
        for fmt in formats.values():
            for p in record_params(fmt.options):
                schema = param_schema(p)
                if schema not in options.setdefault(p.name, []):
                    options[p.name].append(schema)
    properties = {
        "from": {"type": "string", "description": "the step whose result is written (default: the last step)"},
        "path": {"type": "string", "description": "file name pattern with {stem}, {parent} and {name}"},
        "format": {
            "enum": sorted({name for formats in FORMATS.values() for name in formats}),
            "description": "default: from the path's suffix",
        },
        **{name: variants[0] if len(variants) == 1 else {"anyOf": variants} for name, variants in options.items()},
    }
    return {"type": "object", "properties": properties, "required": ["path"], "additionalProperties": False}


def pipeline_schema() -> dict:
    """The JSON Schema (draft 2020-12) of pipeline files, from the registries of this version."""
    inputs_list = {"type": "array", "items": {"type": "string"}, "minItems": 1}
    schema = {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "hht3d pipeline",
        "description": "A declarative hht3d pipeline: load -> process -> export (`hht3d run FILE`).",
        "type": "object",
        "properties": {
            "version": {"const": VERSION, "description": "the schema version"},
            "name": {"type": "string", "minLength": 1, "description": "default: the file's stem"},
            "execution": _object(EXECUTION, description="how the graph runs"),
            "storage_options": {
                "type": "object",
                "description": "options of the fsspec back-end of URL inputs and "
                "outputs (endpoint, region...); never credentials",
            },
            "inputs": {
                "description": "a file, a folder, a glob, a list of them, or {builtin: NAME}",
                "anyOf": [
                    {"type": "string", "minLength": 1},
                    inputs_list,
                    {
                        "type": "object",
                        "properties": {"builtin": {"enum": sorted(builtin_models())}},
                        "required": ["builtin"],
                        "additionalProperties": False,
                    },
                ],
            },
            "steps": {
                "type": "array",
                "items": {"$ref": "#/$defs/step"},
                "minItems": 1,
                "description": "run per input file; a step without from takes the nearest earlier result",
            },
            "outputs": {
                "type": "object",
                "additionalProperties": False,
                "properties": {
                    "folder": {"type": "string", "description": "default: out"},
                    "summary": {"type": "boolean", "default": True, "description": "summary.json and summary.csv"},
                    "allow_outside": {
                        "type": "boolean",
                        "default": False,
                        "description": "let outputs resolve outside folder (default: refused)",
                    },
                    "files": {"type": "array", "items": {"$ref": "#/$defs/output"}},
                },
            },
        },
        "required": ["version", "inputs", "steps", "outputs"],
        "additionalProperties": False,
        "$defs": {"step": _step_schema(), "output": _output_schema(), "gain": _gain_schema()},
    }
    return schema


def schema_text() -> str:
    """:func:`pipeline_schema` as the text of ``pipeline.schema.json`` (keys in the order written)."""
    return json.dumps(pipeline_schema(), indent=2, ensure_ascii=False) + "\n"
