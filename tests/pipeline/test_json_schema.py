"""The JSON Schema of pipeline files: shipped up to date, accepts every example, refuses what the validator refuses."""

import json
from pathlib import Path

import pytest

from hht3d import data_path
from hht3d.pipeline import OPERATIONS
from hht3d.pipeline.document import read_yaml
from hht3d.pipeline.json_schema import pipeline_schema, schema_text
from hht3d.pipeline.validation import FILE_KEYS, OUTPUTS_KEYS, STEP_KEYS, TOP_KEYS

jsonschema = pytest.importorskip("jsonschema")

SHIPPED = data_path("pipeline.schema.json")
EXAMPLES = [*sorted((Path(__file__).resolve().parents[2] / "pipelines").glob("*.yaml")), data_path("demo.yaml")]


@pytest.fixture(scope="module")
def validator():
    schema = pipeline_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def test_shipped_schema_is_the_generated_one():
    assert SHIPPED.read_text(encoding="utf-8") == schema_text(), (
        "hht3d/data/pipeline.schema.json is stale: regenerate it with "
        "python3 -m hht3d schema --output hht3d/data/pipeline.schema.json"
    )


def test_schema_has_the_validators_keys_and_every_operation():
    schema = pipeline_schema()
    assert set(schema["properties"]) == set(TOP_KEYS)
    assert set(schema["properties"]["outputs"]["properties"]) == set(OUTPUTS_KEYS)
    assert set(schema["$defs"]["step"]["properties"]) == set(STEP_KEYS)
    assert set(FILE_KEYS) <= set(schema["$defs"]["output"]["properties"])
    rules = schema["$defs"]["step"]["allOf"]
    assert [rule["if"]["properties"]["op"]["const"] for rule in rules] == list(OPERATIONS)
    for rule, op in zip(rules, OPERATIONS.values()):
        assert set(rule["then"]["properties"]["params"]["properties"]) == {p.name for p in op.params}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_pipeline_is_valid(validator, path):
    document = read_yaml(path.read_text(encoding="utf-8"), str(path))
    assert [e.message for e in validator.iter_errors(json.loads(json.dumps(document)))] == []


@pytest.mark.parametrize(
    "change, where",
    [
        (lambda d: d["steps"][1].update(op="hhtt"), ["steps", 1, "op"]),
        (lambda d: d["steps"][1]["params"].update(max_imfs=100), ["steps", 1, "params", "max_imfs"]),
        (lambda d: d["steps"][1]["params"].update(tol=0), ["steps", 1, "params", "tol"]),
        (lambda d: d["steps"][1]["params"].update(stopping="never"), ["steps", 1, "params", "stopping"]),
        (lambda d: d["steps"][1]["params"].update(max_imf=4), ["steps", 1, "params"]),
        (
            lambda d: d["steps"].append({"op": "filter_signal", "params": {"gain": {"kind": "band_stop", "low": 1}}}),
            ["steps", 2, "params", "gain"],
        ),
        (lambda d: d["outputs"]["files"][0].update(colour="red"), ["outputs", "files", 0]),
        (lambda d: d.update(version=2), ["version"]),
    ],
)
def test_schema_refuses_what_the_validator_refuses(validator, change, where):
    document = {
        "version": 1,
        "inputs": {"builtin": "spot"},
        "steps": [{"op": "signal", "params": {"kind": "mean_curvature"}}, {"op": "hht", "params": {}}],
        "outputs": {"files": [{"path": "{stem}.npz"}]},
    }
    assert list(validator.iter_errors(document)) == []
    change(document)
    errors = list(validator.iter_errors(document))
    assert errors and any(list(e.absolute_path) == where for e in errors), [
        (list(e.absolute_path), e.message) for e in errors
    ]


def test_cli_prints_and_writes_the_schema(tmp_path, capsys):
    from hht3d.cli import main

    assert main(["schema"]) == 0
    assert capsys.readouterr().out == schema_text()
    target = tmp_path / "editor" / "pipeline.schema.json"
    assert main(["schema", "--output", str(target)]) == 0
    assert target.read_text(encoding="utf-8") == schema_text()


def _enums(node):
    if isinstance(node, dict):
        yield from node.get("enum", [])
        for value in node.values():
            yield from _enums(value)
    elif isinstance(node, list):
        for value in node:
            yield from _enums(value)


def test_no_choice_is_a_word_yaml_reads_as_a_boolean():
    """YAML 1.1 (PyYAML) reads on/off/yes/no/true/false unquoted as booleans, so a choice spelled so
    could not be written plainly in a pipeline file ('multiresolution: on' was refused as True)."""
    booleans = {"on", "off", "yes", "no", "true", "false"}  # PyYAML leaves y and n (the axis "y") as text
    words = [value for value in _enums(pipeline_schema()) if isinstance(value, str)]
    assert words, "the schema lists no choices"
    assert not [w for w in words if w.lower() in booleans]
    assert read_yaml("emd: {multiresolution: always}", "test")["emd"]["multiresolution"] == "always"
    assert read_yaml("emd: {multiresolution: on}", "test")["emd"]["multiresolution"] is True  # the trap
