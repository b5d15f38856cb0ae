"""Operations from other packages (hht3d.pipeline.plugins): a distribution installed for the test as a
dist-info folder on sys.path, found by importlib.metadata as any installed package is, declares three
entry points in the group hht3d.operations: a working operation, one taking a built-in's name, and
one whose module does not exist."""

import sys
import textwrap

import numpy as np
import pytest

from hht3d import load
from hht3d.cli import main
from hht3d.errors import PipelineError
from hht3d.geometry.signals import mean_curvature
from hht3d.pipeline import OPERATIONS, operations, parse_pipeline, run_pipeline
from hht3d.pipeline import plugins as plugins_module
from hht3d.pipeline.json_schema import pipeline_schema

PLUGIN = """\
import numpy as np
from hht3d.pipeline import Operation, Param, Slot


def scale_signal(surface, signal, *, factor=2.0):
    return factor * np.asarray(signal)


OPERATIONS = [
    Operation(
        "scale_signal",
        "a signal times a factor",
        (Slot("surface", ("surface",)), Slot("signal", ("signal",))),
        "signal",
        (Param("factor", "float", "the factor", default=2.0, minimum=0),),
        func=scale_signal,
    )
]
CLASH = Operation("emd", "not the real one", (), "signal", (), func=scale_signal)
"""
ENTRY_POINTS = """\
[hht3d.operations]
scale = hht3d_fakeplug:OPERATIONS
clash = hht3d_fakeplug:CLASH
broken = hht3d_not_there:OPERATIONS
"""


@pytest.fixture
def installed(tmp_path, monkeypatch):
    site = tmp_path / "site"
    info = site / "hht3d_fakeplug-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: hht3d-fakeplug\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(ENTRY_POINTS)
    (site / "hht3d_fakeplug.py").write_text(PLUGIN)
    monkeypatch.syspath_prepend(str(site))
    plugins_module._plugins.cache_clear()
    yield
    plugins_module._plugins.cache_clear()
    sys.modules.pop("hht3d_fakeplug", None)


def test_hht3d_ops_lists_the_plugin_with_its_source_and_reports_each_broken_one_in_one_line(installed, capsys):
    assert main(["ops"]) == 0
    out, err = capsys.readouterr()
    assert "scale_signal(surface: surface, signal: signal) -> signal  [plugin: hht3d-fakeplug 0.1]" in out
    assert "    factor  2.0         float >= 0 — the factor" in out
    assert err.splitlines() == [
        "hht3d: warning: plugin 'clash' (hht3d-fakeplug 0.1) declares operation 'emd', the name of a built-in "
        "operation; rename it",
        "hht3d: warning: plugin 'broken' (hht3d-fakeplug 0.1) failed to load: No module named 'hht3d_not_there'",
    ]
    assert operations()["emd"] is OPERATIONS["emd"]  # the built-in stays
    assert "scale_signal" in pipeline_schema()["$defs"]["step"]["properties"]["op"]["enum"]


def test_a_pipeline_runs_the_plugin_operation_once_allowed_and_validates_its_parameters(installed, tmp_path, mesh_file):
    text = textwrap.dedent(f"""\
        version: 1
        execution: {{scheduler: synchronous, progress: false}}
        inputs: {mesh_file}
        steps:
          - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}
          - {{id: scaled, op: scale_signal, params: {{factor: 3}}}}
        outputs:
          folder: {tmp_path / "out"}
          files:
            - {{from: scaled, path: scaled.npz}}
        """)
    plan = parse_pipeline(text)
    refusal = (
        r"step 'scaled' runs op 'scale_signal' of the plugin hht3d-fakeplug 0.1, which runs that package's code; "
        r"pass --allow-plugins \(or set HHT3D_ALLOW_PLUGINS=1\) to run it"
    )
    with pytest.raises(PipelineError, match=f"^{refusal}$"):  # the pipeline file alone cannot allow it
        run_pipeline(plan)
    assert not (tmp_path / "out").exists()  # refused before any output is written
    (row,) = run_pipeline(plan, allow_plugins=True)
    assert row.status == "ok", row.error
    expected = 3 * mean_curvature(load(mesh_file))
    np.testing.assert_allclose(np.load(tmp_path / "out" / "scaled.npz")["signal"], expected, rtol=1e-12)
    with pytest.raises(PipelineError, match=r"parameter factor must be a number >= 0"):
        parse_pipeline(text.replace("factor: 3", "factor: -1"))


def test_without_plugins_an_unknown_op_says_which_failed_to_load(installed):
    with pytest.raises(
        PipelineError,
        match=r"unknown op 'scale_signl'; did you mean 'scale_signal'\?.*"
        r"plugin 'broken' \(hht3d-fakeplug 0.1\) failed to load",
    ):
        plugins_module.operation("scale_signl", "step 2")


@pytest.fixture
def mesh_file(tmp_path):
    from helpers.meshes import icosphere
    from hht3d import Surface
    from hht3d.io import write_ply

    return write_ply(tmp_path / "ball.ply", Surface(*icosphere(2)))


def test_hht3d_run_refuses_a_plugin_step_in_one_line_unless_the_user_allows_it(
    installed, tmp_path, mesh_file, monkeypatch, capsys
):
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        textwrap.dedent(f"""\
            version: 1
            execution: {{scheduler: synchronous, progress: false}}
            inputs: {mesh_file}
            steps:
              - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}
              - {{id: scaled, op: scale_signal}}
            outputs: {{folder: {tmp_path / "out"}, files: [{{from: scaled, path: scaled.npz}}]}}
            """)
    )
    assert main(["run", str(pipeline)]) != 0
    assert capsys.readouterr().err.splitlines()[-1] == (  # after the broken plugins' warnings
        "hht3d: error: step 'scaled' runs op 'scale_signal' of the plugin hht3d-fakeplug 0.1, which runs that "
        "package's code; pass --allow-plugins (or set HHT3D_ALLOW_PLUGINS=1) to run it"
    )
    assert main(["run", str(pipeline), "--allow-plugins"]) == 0
    monkeypatch.setenv("HHT3D_ALLOW_PLUGINS", "1")  # the user's own setting
    assert main(["run", str(pipeline)]) == 0
