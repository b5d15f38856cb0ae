"""Bad pipeline documents (issue 15): YAML that explodes through aliases or nesting, values too long to echo,
pipeline files that are not UTF-8 or not files, syntax errors, a malformed --set.

One table row each, run by :func:`helpers.bad_inputs.run_case` (what a row holds and checks is told there).
"""

from __future__ import annotations

import pytest

from helpers.bad_inputs import PIPELINE, Case, run_case, validate


def _alias_bomb(levels: int) -> str:
    """A YAML flow list whose last item, once its aliases are expanded, holds ``9**levels`` strings."""
    names = "abcdefghijklmnop"[:levels]
    items = [f"&a [{', '.join(['lol'] * 9)}]"]
    items += [f"&{b} [{', '.join([f'*{a}'] * 9)}]" for a, b in zip(names, names[1:])]
    return f"[{', '.join(items)}]"


CASES = {
    # 4. echoed values are cut; YAML aliases cannot explode
    "YAML alias bomb (9^9 values)": Case(
        validate(),
        "expands to more than 100000 values through aliases",
        yaml=f"{PIPELINE}bomb: {_alias_bomb(9)}\n",
        issue=True,
    ),
    "alias bomb below the limit as a parameter": Case(
        validate(),
        "parameter kind must be one of",
        issue=True,
        yaml=PIPELINE.replace("kind: mean_curvature", f"kind: {_alias_bomb(5)}"),
    ),
    "recursive alias": Case(validate(), "an alias refers to its own anchor", yaml=PIPELINE + "loop: &l [*l]\n"),
    "megabyte value": Case(
        validate("steps.curvature.params.kind=" + "x" * 1_000_000), "parameter kind must be one of", issue=True
    ),
    "deeply nested YAML": Case(validate(), "the YAML is nested too deeply", yaml=PIPELINE + "deep: " + "[" * 3000),
    # the pipeline file and its text
    "pipeline that is not UTF-8": Case(("validate", "<in>/latin1.yaml"), "byte 20 is not UTF-8 text"),
    "pipeline that is a folder": Case(("validate", "<in>"), "cannot read the pipeline (Is a directory)"),
    "empty pipeline": Case(validate(), "got an empty file", yaml=""),
    "YAML syntax error": Case(
        validate(),
        "pipeline.yaml:6:3: YAML syntax error: while parsing a flow mapping",
        yaml=PIPELINE.replace("mean_curvature}}", "mean_curvature}"),
    ),
    "--set without =": Case(validate("steps.hht.params.max_imfs"), "expected KEY.PATH=VALUE"),
    "step id of 100 characters": Case(validate("steps.hht.id=" + "h" * 100), "step id must be 1 to 64 letters"),
    "a plain list of 200,000 inputs": Case(
        validate(),
        "the YAML holds more than 100000 values",
        yaml=PIPELINE.replace('inputs: "<in>/good.ply"', "inputs: [" + ", ".join(["a.ply"] * 200_000) + "]"),
    ),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_input(name, inputs, tmp_path, capfd, monkeypatch):
    run_case(CASES[name], inputs, tmp_path, capfd, monkeypatch)
