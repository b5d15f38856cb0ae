"""Invalid pipelines say what to fix and write nothing (hht3d.pipeline.validation); valid ones wire their steps into
a plan."""

import textwrap
from pathlib import Path

import pytest

from helpers.pipelines import GOOD, _run
from hht3d.pipeline import load_pipeline, parse_pipeline

# -- invalid pipelines: a specific message, nothing written ------------------------------------------

EMD_STEP = "    op: emd\n"
MORE_STEPS = "  - {id: hht, op: hht}\n  - {id: smooth, op: filter_geometry, params: {gain: {kind: constant}}}\noutputs:"

#: case: (edits of GOOD as (old, new) pairs, expected part of the message)
INVALID = {
    "yaml syntax": ([(EMD_STEP, EMD_STEP + "   params: [\n")], "pipeline.yaml:9:4: YAML syntax error"),
    "unknown op": ([("op: emd", "op: emdd")], "unknown op 'emdd'; did you mean 'emd'?"),
    "unknown parameter": (
        [("max_imfs: 2", "max_imf: 2")],
        ("pipeline.yaml:9: step 'emd' (op emd): unknown parameter 'max_imf'; did you mean 'max_imfs'?"),
    ),
    "unknown top-level key": ([("steps:", "step:")], "unknown key 'step' in the pipeline; did you mean 'steps'?"),
    "wrong type": (
        [("max_imfs: 2", "max_imfs: two")],
        "parameter max_imfs must be an integer in [0, 64]; got 'two' (a string)",
    ),
    "out of range": ([("max_imfs: 2", "ratio: 1.5")], "parameter ratio must be a number in (0.5, 1]; got 1.5"),
    "bad choice": (
        [("kind: mean_curvature", "kind: mean_curvatur")],
        "parameter kind must be one of mean_curvature, gaussian_curvature",
    ),
    "missing reference": (
        [(EMD_STEP, EMD_STEP + "    from: {signal: curvture}\n")],
        "from.signal refers to unknown step 'curvture'; did you mean 'curvature'?",
    ),
    "reference of the wrong kind": (
        [(EMD_STEP, EMD_STEP + "    from: {signal: load}\n")],
        "from.signal: step 'load' makes surface, but signal needs signal",
    ),
    "cyclic reference": (
        [("    op: signal\n", "    op: signal\n    from: {surface: smooth}\n"), ("outputs:", MORE_STEPS)],
        "steps 'curvature' -> 'smooth' -> 'hht' -> 'curvature' form a cycle (each uses the next)",
    ),
    "no earlier input": (
        [("  - id: curvature\n    op: signal\n    params: {kind: mean_curvature}\n", "")],
        (
            "step 'emd' (op emd) needs signal input 'signal', and no earlier step makes one; add a "
            "step with op filter_signal or signal before it"
        ),
    ),
    "duplicate id": ([("id: emd", "id: curvature")], "two steps have the id 'curvature'"),
    "missing input file": ([("inputs: ", "inputs: missing_")], "no such file or folder"),
    "unsupported version": (
        [("version: 1", "version: 2")],
        "unsupported pipeline version 2; this hht3d reads version 1",
    ),
    "bad gain": (
        [("outputs:", MORE_STEPS), ("kind: constant", "kind: band_stop, low: 5, hihg: 9")],
        "gain band_stop has no parameter 'hihg'; did you mean 'high'?",
    ),
    "output of the wrong kind": (
        [("_imfs.npz", "_imfs.png")],
        "step 'emd' makes emd, which can be written as npz, ply, las, laz, vtu, vtp, not 'png'",
    ),
    "unknown output field": (
        [
            ("outputs:", MORE_STEPS),
            ('{from: emd, path: "{stem}_imfs.npz"}', '{from: hht, path: "{stem}.ply", field: frequncy_1}'),
        ],
        "unknown field 'frequncy_1'",
    ),
    "unknown placeholder": ([("{stem}_imfs", "{steam}_imfs")], "unknown placeholder {steam}"),
}


@pytest.mark.parametrize("case", INVALID)
def test_invalid_pipeline_names_the_problem_and_writes_nothing(case, tmp_path, mesh_file, capsys):
    edits, message = INVALID[case]
    text = GOOD.format(mesh=mesh_file, out=tmp_path / "out")
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "pipeline.yaml"
    path.write_text(text)
    assert _run(path) == 1
    err = capsys.readouterr().err
    assert err.startswith("hht3d: error: ") and err.count("\n") == 1, err
    assert message in err
    assert not (tmp_path / "out").exists()


def test_colliding_output_paths_are_rejected(tmp_path, folder):
    text = GOOD.format(mesh=folder, out=tmp_path / "out").replace("{stem}_imfs", "imfs")
    with pytest.raises(Exception, match=r"inputs .*part0.ply and .*part1.ply would both write .*imfs.npz"):
        parse_pipeline(text)


def test_bad_override_path_says_what_exists(tmp_path, mesh_file):
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=mesh_file, out=tmp_path / "out"))
    with pytest.raises(
        Exception, match="--set steps.emdd.params.max_imfs=3: steps.emdd matches no list item.*did you mean 'emd'"
    ):
        load_pipeline(path, ["steps.emdd.params.max_imfs=3"])
    with pytest.raises(
        Exception,
        match=r"--set steps.emd.params.max_imfs=-1: step 'emd' \(op emd\): parameter "
        r"max_imfs must be an integer in \[0, 64\]",
    ):
        load_pipeline(path, ["steps.emd.params.max_imfs=-1"])


# -- the plan -----------------------------------------------------------------------------------
def test_linear_chain_wires_itself_and_explicit_references_win(tmp_path, mesh_file):
    text = textwrap.dedent(f"""\
        version: 1
        execution: {{seed: 7}}
        inputs: {mesh_file}
        steps:
          - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}
          - {{id: height, op: signal, params: {{kind: z}}}}
          - {{id: decompose, op: eemd, from: curvature, params: {{ensemble_size: 2, max_imfs: 1}}}}
          - {{id: hht, op: hht}}
          - {{id: peaks, op: features}}
          - {{id: flat, op: filter_signal, params: {{gain: {{kind: low_pass, cutoff: 2.0}}}}}}
          - {{id: rebuilt, op: reconstruct}}
        outputs:
          files: [{{from: rebuilt, path: "{{stem}}.ply"}}]
        """)
    plan = parse_pipeline(text)
    refs = {s.id: s.refs for s in plan.steps}
    assert plan.steps[0].id == "load"  # implicit first step
    assert refs["decompose"] == {"surface": "load", "signal": "curvature"}
    assert refs["hht"] == {"surface": "load", "signal": "height"}  # the nearest earlier signal
    assert refs["peaks"] == {"surface": "load", "imfs": "hht"}
    assert refs["rebuilt"] == {"surface": "load", "signal": "flat"}
    assert plan.step("decompose").params["seed"] == 7  # execution.seed
    assert plan.outputs[0].format.name == "ply" and plan.folder == Path("out")
    text = plan.describe()
    assert "hht        hht(surface=load, signal=height) -> hht" in text
    assert "ensemble_size=2, max_imfs=1" in text


def test_forward_references_are_ordered(mesh_file):
    text = textwrap.dedent(f"""\
        version: 1
        inputs: {mesh_file}
        steps:
          - {{id: hht, op: hht, from: {{signal: curvature}}}}
          - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}
        outputs:
          files: [{{path: "{{stem}}.npz"}}]
        """)
    plan = parse_pipeline(text)
    assert [s.id for s in plan.steps] == ["load", "curvature", "hht"]
    assert plan.outputs[0].step == "hht"  # default: the last step to run


def test_builtin_demo_model_is_an_input():
    plan = parse_pipeline(
        "version: 1\ninputs: {builtin: spot}\nsteps: [{op: signal, params: {kind: x}}]\n"
        "outputs: {files: [{path: a.npz}]}"
    )
    assert plan.inputs[0].name == "spot.ply" and plan.inputs[0].is_file()
    with pytest.raises(Exception, match="unknown builtin model 'spott'; did you mean 'spot'"):
        parse_pipeline("version: 1\ninputs: {builtin: spott}\nsteps: [{op: signal}]\n")
