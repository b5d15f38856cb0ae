"""The ``hht3d`` command: subcommands, output and exit codes."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from meshes import icosphere

from hht3d import Surface
from hht3d.cli import demo_pipeline_path, main
from hht3d.io import write_ply
from hht3d.pipeline import OPERATIONS

PIPELINE = """\
version: 1
inputs: {mesh}
steps:
  - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}
  - {{id: hht, op: hht, params: {{max_imfs: 2}}}}
outputs:
  folder: {out}
  files:
    - {{from: hht, path: "{{stem}}_hht.npz"}}
"""


@pytest.fixture
def mesh_file(tmp_path):
    v, f = icosphere(2)
    path = tmp_path / "bumpy.ply"
    write_ply(path, Surface(v * (1 + 0.06 * np.sin(5 * v[:, [0]])), f, name="bumpy"))
    return path


@pytest.fixture
def pipeline(tmp_path, mesh_file):
    path = tmp_path / "pipeline.yaml"
    path.write_text(PIPELINE.format(mesh=mesh_file, out=tmp_path / "out"))
    return path


def test_run_succeeds_with_exit_code_0(pipeline, tmp_path, capsys):
    assert main(["run", str(pipeline), "--scheduler", "synchronous", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "bumpy.ply: ok, 162 vertices, 2 IMFs" in out
    assert f"wrote {tmp_path / 'out' / 'bumpy_hht.npz'}" in out
    assert (tmp_path / "out" / "summary.json").is_file()


def test_set_overrides_a_parameter_and_resume_skips(pipeline, tmp_path, capsys):
    args = ["run", str(pipeline), "--scheduler", "synchronous", "--quiet", "--set", "steps.hht.params.max_imfs=1"]
    assert main(args) == 0
    assert "1 IMFs" in capsys.readouterr().out
    assert np.load(tmp_path / "out" / "bumpy_hht.npz")["imfs"].shape[0] == 1
    assert main([*args, "--resume"]) == 0
    assert "skipped (outputs exist)" in capsys.readouterr().out


def test_failures_exit_1_with_one_line(pipeline, tmp_path, capsys):
    assert main(["run", str(pipeline), "--quiet", "--set", "steps.hht.params.max_imfs=-2"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "max_imfs must be an integer in [0, 64]; got -2" in err
    assert main(["run", str(tmp_path / "missing.yaml")]) == 1
    assert "cannot read the pipeline" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_usage_errors_exit_2(pipeline, capsys):
    for argv in (["run"], ["run", str(pipeline), "--scheduler", "bogus"], ["frobnicate"], []):
        with pytest.raises(SystemExit) as stop:
            main(argv)
        assert stop.value.code == 2
    assert "usage: hht3d" in capsys.readouterr().err


def test_validate_prints_the_planned_graph_and_runs_nothing(pipeline, tmp_path, capsys):
    assert main(["validate", str(pipeline), "--set", "steps.hht.params.riesz_tasks=3"]) == 0
    out = capsys.readouterr().out
    assert "hht        hht(surface=load, signal=curvature) -> hht" in out
    assert "max_imfs=2, riesz_tasks=3" in out
    assert "dask graph" not in out  # validation builds no graph (issue 15)
    assert "output locations checked; nothing was run" in out
    assert not (tmp_path / "out").exists()
    assert main(["validate", str(pipeline), "--set", "steps.hht.op=hhtt"]) == 1
    assert "unknown op 'hhtt'; did you mean 'hht'?" in capsys.readouterr().err


def test_ops_lists_every_operation_with_parameters_and_defaults(capsys):
    assert main(["ops"]) == 0
    out = capsys.readouterr().out
    for name in OPERATIONS:
        assert f"\n{name}(" in f"\n{out}"
    assert "max_imfs" in out and "sd | rfg | s_number | fixed" in out
    assert "hht       png" in out  # the output formats
    assert main(["ops", "emd"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "emd(surface: surface, signal: signal) -> emd"
    assert any(line.split()[:2] == ["max_imfs", "10"] for line in lines)
    assert main(["ops", "emdd"]) == 1
    assert "unknown op 'emdd'; did you mean 'emd'?" in capsys.readouterr().err


def test_info_describes_a_file(mesh_file, tmp_path, capsys):
    assert main(["info", str(mesh_file)]) == 0
    assert "162" in capsys.readouterr().out
    assert main(["info", str(tmp_path / "none.ply")]) == 1
    assert "no such file" in capsys.readouterr().err


def test_demo_runs_the_shipped_pipeline_into_out(tmp_path, capsys):
    """The README's main job: ``hht3d demo --out out/demo``, on the shipped model."""
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--scheduler", "synchronous", "--quiet"]) == 0
    expected = {f"spot_{name}" for name in ("hht.ply", "hht.npz", "signal.ply", "imf_1.ply", "frequency_1.ply",
                                            "hht.png", "spectrum.png", "hht.html")}
    assert {p.name for p in out.iterdir()} == expected
    assert "spot.ply: ok, 2930 vertices" in capsys.readouterr().out


def test_pipelines_demo_is_the_shipped_demo():
    example = Path(__file__).resolve().parents[1] / "pipelines" / "demo.yaml"
    assert example.read_text() == demo_pipeline_path().read_text()


def test_module_entry_point():
    done = subprocess.run([sys.executable, "-m", "hht3d", "ops", "load"], capture_output=True, text=True, check=False,
                          timeout=120)
    assert done.returncode == 0 and done.stdout.startswith("load(file: file) -> surface")
