"""Bad parameter values (issue 15): numbers above their upper bounds, refused without building the graph;
facts cheap to know, checked by validate; any value of a pipeline replaced by an odd one.

One table row each, run by :func:`helpers.bad_inputs.run_case` (what a row holds and checks is told there).
"""

from __future__ import annotations

import copy
import json

import pytest
import yaml

from helpers.bad_inputs import PIPELINE, Case, _substitute, run, run_case, validate
from hht3d.errors import HHT3DError
from hht3d.pipeline import parse_pipeline


def _no_graph(monkeypatch) -> None:
    """Validation must not build the task graph (10,000 EEMD members took 105 s to build)."""

    def refuse(*args, **kwargs):
        raise AssertionError("validate built the task graph")

    monkeypatch.setattr("hht3d.pipeline.runner.pipeline_graph", refuse)
    monkeypatch.setattr("hht3d.graph.stages.Builder.task", refuse)


CASES = {
    # 3. upper bounds, checked without building the graph
    "riesz_tasks: 100000": Case(
        validate("steps.hht.params.riesz_tasks=100000"),
        "riesz_tasks must be an integer in [1, 64]; got 100000",
        issue=True,
    ),
    "riesz_tasks: 5000 in run": Case(
        run("steps.hht.params.riesz_tasks=5000"), "riesz_tasks must be an integer in", issue=True
    ),
    "ensemble_size: 1e9": Case(
        validate(),
        "ensemble_size must be an integer in [1, 1000]; got 1000000000.0",
        yaml=PIPELINE.replace("max_imfs: 2", "ensemble_size: 1e9"),
        issue=True,
    ),
    "ensemble_size: 1000000000": Case(
        validate("steps.hht.params.ensemble_size=1000000000"),
        "ensemble_size must be an integer in [1, 1000]",
        issue=True,
    ),
    "the largest ensemble validates without a graph": Case(
        validate("steps.hht.params.ensemble_size=1000", "steps.hht.params.riesz_tasks=64"),
        "",
        0,
        (),
        fault=_no_graph,
        issue=True,
    ),
    "max_imfs: 1000": Case(
        validate("steps.hht.params.max_imfs=1000"), "max_imfs must be an integer in [0, 64]", issue=True
    ),
    "eigenpairs: 100000": Case(
        validate("steps.hht.params.eigenpairs=100000"), "eigenpairs must be an integer in [1, 2000]", issue=True
    ),
    "--workers 100000": Case((*run(), "--workers", "100000"), "workers must be an integer in [1, 256]", issue=True),
    "execution.workers: 100000": Case(
        validate("execution.workers=100000"), "workers must be an integer in [1, 256]", issue=True
    ),
    "sd_threshold: 1e6": Case(
        validate("steps.hht.params.sd_threshold=1e6"), "sd_threshold must be a number in [0, 10]"
    ),
    "seed: 2**64": Case(validate("execution.seed=18446744073709551616"), "seed must be an integer in [0, 4294967295]"),
    "max_sifts: 10**9": Case(validate("steps.hht.params.max_sifts=1000000000"), "max_sifts must be an integer in"),
    "n_neighbors: 10**6": Case(validate("steps.load.params.n_neighbors=1000000"), "n_neighbors must be an integer in"),
    # facts cheap to know are checked by validate
    "eigenpairs above the vertex count": Case(
        validate("steps.hht.params.potential=spectral"), "eigenpairs: 300 needs at least 301 vertices, but", issue=True
    ),
    "eigenpairs above the vertex count of a baseline": Case(
        validate(
            "steps.hht.op=manifold_harmonics_filter",
            "steps.hht.params={gain: {kind: constant}, eigenpairs: 162}",
            "outputs.files=[{path: x.ply}]",
        ),
        "eigenpairs: 162 needs at least 163 vertices",
    ),
    "field imf_9 with max_imfs: 2": Case(
        validate("outputs.files=[{path: x.ply, field: imf_9}]"),
        "field imf_9 needs 9 IMFs, but step 'hht' makes at most max_imfs: 2",
        issue=True,
    ),
    "gain without cutoff": Case(
        validate(
            "steps.hht.op=filter_signal",
            "steps.hht.params={gain: {kind: low_pass}}",
            "steps.hht.from=null",
            "outputs.files=[{path: x.npz}]",
        ),
        "gain low_pass needs cutoff: {kind: low_pass, cutoff: ...}",
        issue=True,
    ),
    "unknown EMD option (YAML side)": Case(
        validate("steps.hht.params.max_imf=2"), "unknown parameter 'max_imf'; did you mean 'max_imfs'?", issue=True
    ),
    "spectrum figure of max_imfs 0": Case(
        validate("steps.hht.params.max_imfs=0", "outputs.files=[{path: x.png, figure: spectrum}]"),
        "a spectrum figure needs IMFs",
    ),
    "malformed --address": Case((*run(), "--address", "http://[::1"), "cannot reach the Dask scheduler"),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_input(name, inputs, tmp_path, capfd, monkeypatch):
    run_case(CASES[name], inputs, tmp_path, capfd, monkeypatch)


# -- every value of a pipeline replaced by an odd one ---------------------------------------------------
FULL = {
    "version": 1,
    "name": "odd",
    "execution": {"scheduler": "threads", "workers": 2, "progress": False, "seed": 3},
    "inputs": ["<in>/good.ply"],
    "steps": [
        {"id": "load", "op": "load", "params": {"clean": True, "laplacian": "cotan", "n_neighbors": 20}},
        {"id": "curvature", "op": "signal", "params": {"kind": "mean_curvature"}},
        {
            "id": "hht",
            "op": "hht",
            "from": {"signal": "curvature"},
            "params": {"max_imfs": 2, "tol": 0.001, "ensemble_size": 3, "riesz_tasks": 2},
        },
        {"id": "smooth", "op": "filter_geometry", "params": {"gain": {"kind": "band_stop", "low": 1, "high": 2}}},
        {"id": "features", "op": "features", "from": "hht", "params": {"ratio": 0.8}},
    ],
    "outputs": {
        "folder": "<out>",
        "summary": True,
        "files": [
            {"from": "hht", "path": "{stem}_hht.ply", "field": "imf_1", "cmap": "viridis"},
            {"from": "hht", "path": "{stem}.png", "figure": "hht", "view": "front"},
            {"from": "features", "path": "{stem}_features.npz"},
        ],
    },
}
ODD = {
    "list": [1],
    "mapping": {"a": 1},
    "null": None,
    "negative": -1,
    "huge number": 10**30,
    "long string": "x" * 10_000,
}


def _places(node, path=()):
    """The path of every value in a nested document."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        yield (*path, key)
        yield from _places(value, (*path, key))


@pytest.mark.parametrize("odd", ODD)
def test_any_value_replaced_by_an_odd_one_is_a_clear_error(odd, inputs, tmp_path):
    document = json.loads(_substitute(json.dumps(FULL), {"in": inputs, "out": tmp_path / "out"}))
    parse_pipeline(yaml.safe_dump(document))  # the document itself is valid
    for place in _places(document):
        changed = copy.deepcopy(document)
        node = changed
        for key in place[:-1]:
            node = node[key]
        node[place[-1]] = ODD[odd]
        try:
            parse_pipeline(yaml.safe_dump(changed))
        except HHT3DError as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 1000, (place, str(exc)[:300])
    assert not (tmp_path / "out").exists()
