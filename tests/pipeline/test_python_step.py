"""The python step (hht3d.pipeline.python_step): a module written to tmp_path and put on sys.path, called on
an hht step's result; refused unless the user allows code, one line for each way the function can be wrong."""

import sys
import textwrap

import numpy as np
import pytest

from hht3d.cli import main
from hht3d.errors import PipelineError
from hht3d.io import load
from hht3d.pipeline import parse_pipeline, run_pipeline
from hht3d.results import load_result

MODULE = """\
import numpy as np

IMPORTED = True


def first_imf(result):
    return result.imfs[0] * 2


def its_surface(result):
    return result.surface


def boom(result):
    raise ValueError("no IMFs wanted")


def words(result):
    return "not a signal"


NOT_CALLABLE = 3
"""


@pytest.fixture
def tools(tmp_path, monkeypatch):
    site = tmp_path / "site"
    site.mkdir()
    (site / "hht3d_labtools.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(site))
    sys.modules.pop("hht3d_labtools", None)
    yield "hht3d_labtools"
    sys.modules.pop("hht3d_labtools", None)


def _text(mesh_file, out, *steps):
    lines = "".join(f"  - {step}\n" for step in steps)
    return (
        "version: 1\nexecution: {scheduler: synchronous, progress: false}\n"
        f"inputs: {mesh_file}\nsteps:\n  - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}\n"
        f"  - {{id: hht, op: hht, params: {{max_imfs: 2}}}}\n{lines}"
        f"outputs:\n  folder: {out}\n  summary: false\n  files:\n    - {{from: hht, path: hht.npz}}\n"
    )


def test_a_python_step_is_refused_without_opt_in_then_makes_a_signal_and_a_surface(tools, tmp_path, mesh_file):
    out = tmp_path / "out"
    text = _text(
        mesh_file,
        out,
        "{id: doubled, op: python, from: hht, params: {function: 'hht3d_labtools:first_imf'}}",
        "{id: shape, op: python, from: hht, params: {function: 'hht3d_labtools:its_surface', output: surface}}",
    )
    text += "    - {from: doubled, path: doubled.npz}\n    - {from: shape, path: shape.ply}\n"
    plan = parse_pipeline(text)
    assert [plan.step(s).kind for s in ("doubled", "shape")] == ["signal", "surface"]
    assert "hht3d_labtools" not in sys.modules  # validation imports nothing
    with pytest.raises(PipelineError) as refused:
        run_pipeline(plan)
    assert str(refused.value) == (
        "step 'doubled' is a python step calling hht3d_labtools:first_imf, which runs that code; "
        "pass --allow-plugins (or set HHT3D_ALLOW_PLUGINS=1) to run it"
    )
    assert "hht3d_labtools" not in sys.modules and not out.exists()  # refused before running any code
    (row,) = run_pipeline(plan, allow_plugins=True)
    assert row.status == "ok", row.error
    result = load_result(out / "hht.npz")
    np.testing.assert_array_equal(np.load(out / "doubled.npz")["signal"], 2 * result.imfs[0])
    assert load(out / "shape.ply", clean=False).n_vertices == result.surface.n_vertices


@pytest.mark.parametrize(
    ("function", "message"),
    [
        ("hht3d_labtools", r":\d+: step 'p' \(op python\): parameter function must be module:function, e\.g\. "),
        ("hht3d_labtools:first imf", r"parameter function must be module:function.*got 'hht3d_labtools:first imf'$"),
    ],
)
def test_a_function_that_is_not_module_colon_name_is_refused_at_validation(
    tools, tmp_path, mesh_file, function, message
):
    text = _text(mesh_file, tmp_path / "out", f"{{id: p, op: python, params: {{function: '{function}'}}}}")
    with pytest.raises(PipelineError, match=message):
        parse_pipeline(text)


@pytest.mark.parametrize(
    ("function", "message"),
    [
        (
            "hht3d_not_a_module:f",
            "step 'p': python function hht3d_not_a_module:f: module 'hht3d_not_a_module' does not import: "
            "ModuleNotFoundError: No module named 'hht3d_not_a_module'",
        ),
        (
            "hht3d_labtools:second_imf",
            "step 'p': python function hht3d_labtools:second_imf: module 'hht3d_labtools' has no attribute "
            "'second_imf'",
        ),
        (
            "hht3d_labtools:NOT_CALLABLE",
            "step 'p': python function hht3d_labtools:NOT_CALLABLE: 'NOT_CALLABLE' is 3, not a function",
        ),
    ],
)
def test_a_function_that_cannot_be_found_stops_the_run_in_one_line_before_computing(
    tools, tmp_path, mesh_file, monkeypatch, function, message
):
    out = tmp_path / "out"
    plan = parse_pipeline(_text(mesh_file, out, f"{{id: p, op: python, params: {{function: '{function}'}}}}"))
    monkeypatch.setenv("HHT3D_ALLOW_PLUGINS", "1")  # the user's own opt-in
    with pytest.raises(PipelineError) as stopped:
        run_pipeline(plan)
    assert str(stopped.value) == message
    assert not out.exists()


@pytest.mark.parametrize(
    ("function", "error"),
    [
        ("boom", "ValueError: no IMFs wanted"),
        (
            "words",
            "PipelineError: python function hht3d_labtools:words returned str 'not a signal', not a 1-D "
            "array of numbers (its step has output: signal)",
        ),
    ],
)
def test_a_function_that_raises_or_returns_another_kind_fails_its_step_for_the_input(
    tools, tmp_path, mesh_file, function, error
):
    text = _text(
        mesh_file, tmp_path / "out", f"{{id: p, op: python, params: {{function: 'hht3d_labtools:{function}'}}}}"
    )
    (row,) = run_pipeline(parse_pipeline(text + "    - {from: p, path: p.npz}\n"), allow_plugins=True)
    assert (row.status, row.step, row.source, row.error) == ("failed", "p", str(mesh_file), error)


def test_hht3d_run_refuses_a_python_step_in_one_line_and_runs_it_with_allow_plugins(tools, tmp_path, mesh_file, capsys):
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        textwrap.dedent(
            _text(mesh_file, tmp_path / "out", "{op: python, params: {function: 'hht3d_labtools:first_imf'}}")
        )
    )
    assert main(["run", str(pipeline)]) != 0
    assert capsys.readouterr().err.splitlines() == [
        "hht3d: error: step 'python' is a python step calling hht3d_labtools:first_imf, which runs that code; "
        "pass --allow-plugins (or set HHT3D_ALLOW_PLUGINS=1) to run it"
    ]
    assert main(["run", str(pipeline), "--allow-plugins"]) == 0
