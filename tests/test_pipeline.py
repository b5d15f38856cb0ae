"""YAML pipelines: the examples run, invalid pipelines say what to fix, numbers match the graph API."""
import json
import textwrap
from pathlib import Path

import numpy as np
import pytest
from helpers.meshes import fibonacci_sphere, icosphere

from helpers.results import assert_same_hht, hht_arrays_from_ply
from helpers.pages import field_values, page_data
from helpers.folders import dead_writers_part, produced_names
from hht3d import Surface, graph
from hht3d.apps import (HighBoost, LowPass, PiecewiseLinear, filter_geometry, filter_signal, hks_features,
                        imf_enhancement, manifold_harmonics_filter, prominent_features, reconstruct)
from hht3d.cli import main
from hht3d.decomposition import eemd, emd
from hht3d.transform import HHTResult, hht
from hht3d.io import load, write_ply
from hht3d.spectral.monogenic_signal import monogenic
from hht3d.geometry.signals import mean_curvature
from hht3d.pipeline import OPERATIONS, load_pipeline, parse_pipeline, run_pipeline

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "pipelines").glob("*.yaml"))
FAST = ["--scheduler", "synchronous", "--quiet"]


def _bumpy(subdivisions=2, waves=5, scale=1.0):
    v, f = icosphere(subdivisions)
    return scale * v * (1 + 0.06 * np.sin(waves * v[:, [0]]) * np.cos(4 * v[:, [1]])), f


@pytest.fixture
def mesh_file(tmp_path):
    path = tmp_path / "in" / "bumpy.ply"
    path.parent.mkdir(exist_ok=True)
    write_ply(path, Surface(*_bumpy(), name="bumpy"))
    return path


@pytest.fixture
def cloud_file(tmp_path):
    path = tmp_path / "in" / "cloud.ply"
    path.parent.mkdir(exist_ok=True)
    points = fibonacci_sphere(300)
    write_ply(path, Surface(points * (1 + 0.06 * np.sin(5 * points[:, [0]])), name="cloud"))
    return path


@pytest.fixture
def folder(tmp_path):
    path = tmp_path / "scans"
    path.mkdir()
    for i in range(2):
        write_ply(path / f"part{i}.ply", Surface(*_bumpy(waves=5 + i, scale=1 + i)))
    return path


def assert_output_fits(path: Path, n_vertices: int) -> None:
    """An output file holds data of its input: per-vertex arrays of the right length, finite
    values, a PLY with every vertex, an HTML page whose fields have every vertex, a PNG
    that is not blank."""
    assert path.is_file(), path
    if path.suffix == ".npz":
        with np.load(path) as data:
            per_vertex = [k for k in data.files if data[k].ndim >= 1 and data[k].shape[-1] == n_vertices
                          or data[k].ndim >= 1 and len(data[k]) == n_vertices]
            assert per_vertex, (path, data.files)
            for key in data.files:  # numbers are finite (a result also names its Laplacian)
                assert not np.issubdtype(data[key].dtype, np.number) or np.all(np.isfinite(data[key])), (path, key)
    elif path.suffix == ".ply":
        surface = load(path, clean=False)
        assert surface.n_vertices == n_vertices, path
        for key, values in surface.attributes.items():
            assert values.shape == (n_vertices,) and np.all(np.isfinite(values)), (path, key)
    elif path.suffix == ".html":
        data = page_data(path)  # test inputs are far below the viewer's decimation budget
        for spec in data["fields"]:
            values = field_values(data, spec["name"])
            assert np.all(np.isfinite(values)) and len(values) == n_vertices, (path, spec["name"])
    else:
        from PIL import Image

        with Image.open(path) as image:
            assert np.asarray(image.convert("L"), dtype=float).std() > 10, path


def _run(pipeline, *options):
    return main(["run", str(pipeline), *FAST, *options])


def _fast_overrides(path) -> list[str]:
    """Few IMFs for every decomposition of an example, to keep the tests short."""
    plan = load_pipeline(path, ["inputs={builtin: spot}"])  # any input will do here
    return [f"steps.{s.id}.params.max_imfs=2" for s in plan.steps if s.op.name in ("emd", "eemd", "hht")]


# -- the examples ------------------------------------------------------------------------------
def test_examples_are_there():
    assert {p.name for p in EXAMPLES} >= {"demo.yaml", "dataset_features.yaml", "filtering.yaml",
                                          "point_cloud.yaml"}


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs_and_writes_its_outputs(example, tmp_path, mesh_file, cloud_file, folder):
    inputs = {"point_cloud": cloud_file, "dataset_features": folder}.get(example.stem, mesh_file)
    out = tmp_path / "out"
    overrides = [f"inputs={inputs}", f"outputs.folder={out}", *_fast_overrides(example)]
    assert _run(example, *[a for o in overrides for a in ("--set", o)]) == 0
    plan = load_pipeline(example, overrides)
    sources = sorted(inputs.iterdir()) if inputs.is_dir() else [inputs]
    for source in sources:
        n = load(source).n_vertices
        for path in plan.output_paths(source):
            assert_output_fits(path, n)
    if plan.summary:
        rows = json.loads((out / "summary.json").read_text())
        assert [r["status"] for r in rows] == ["ok"] * len(sources)
    assert not list(out.rglob("*.part"))


def test_point_cloud_example_keeps_points_and_fields(tmp_path, cloud_file):
    out = tmp_path / "out"
    example = next(p for p in EXAMPLES if p.stem == "point_cloud")
    _run(example, "--set", f"inputs={cloud_file}", "--set", f"outputs.folder={out}",
         "--set", "steps.hht.params.max_imfs=2")
    result = load(out / "cloud_hht.ply", clean=False)
    assert result.faces is None and result.n_vertices == 300
    assert {"signal", "imf_1", "frequency_1", "residue"} <= set(result.attributes)
    cloud = load(cloud_file, n_neighbors=30)
    expected = hht(cloud, mean_curvature(cloud), emd={"max_imfs": 2})
    np.testing.assert_array_equal(result.vertices, cloud.vertices)
    with np.load(out / "cloud_hht.npz") as saved:
        assert_same_hht(saved, expected)
    assert_same_hht(hht_arrays_from_ply(result.attributes), expected)


def test_filtering_example_moves_vertices_and_keeps_faces(tmp_path, mesh_file):
    out = tmp_path / "out"
    example = next(p for p in EXAMPLES if p.stem == "filtering")
    _run(example, "--set", f"inputs={mesh_file}", "--set", f"outputs.folder={out}",
         "--set", "steps.smooth.params.gain={kind: low_pass, cutoff: 1.0}",  # the bumps are at ~5 rad/unit
         "--set", "steps.enhance.params.gain={kind: high_boost, cutoff: 3.0, factor: 2.0, width: 1.0}")
    original, smooth = load(mesh_file, clean=False), load(out / "bumpy_smooth.ply", clean=False)
    np.testing.assert_array_equal(smooth.faces, original.faces)
    assert np.abs(smooth.vertices - original.vertices).max() > 1e-4
    # the same filter through the Python API: Riesz round-off (1e-12) moves the gains and so the
    # vertices by far less than 1e-9 of the model size
    surface = load(mesh_file)
    result = hht(surface, mean_curvature(surface), emd={"max_imfs": 6})
    expected = filter_geometry(result, LowPass(cutoff=1.0))
    np.testing.assert_allclose(smooth.vertices, expected.vertices, rtol=0, atol=1e-9)
    enhanced = filter_geometry(result, HighBoost(cutoff=3.0, factor=2.0, width=1.0), interior_weight=0.01, boundary_weight=1.0)
    assert np.abs(enhanced.vertices - original.vertices).max() > 1e-4  # the boost acts: not an unchanged copy
    np.testing.assert_allclose(load(out / "bumpy_enhanced.ply", clean=False).vertices, enhanced.vertices,
                               rtol=0, atol=1e-9)


# -- same numbers through the CLI, the Python pipeline API and the graph API ------------------------
def test_cli_pipeline_and_graph_api_give_the_same_numbers(tmp_path, mesh_file):
    demo = next(p for p in EXAMPLES if p.stem == "demo")
    overrides = [f"inputs={mesh_file}", "steps.hht.params.max_imfs=3", "outputs.files=[{path: x.npz}]"]
    cli = [*overrides, f"outputs.folder={tmp_path / 'cli'}"]
    assert _run(demo, *[a for o in cli for a in ("--set", o)]) == 0
    plan = load_pipeline(demo, [*overrides, f"outputs.folder={tmp_path / 'api'}"])
    (row,) = run_pipeline(plan, scheduler="synchronous", progress=False)

    surface = graph.load(mesh_file)
    lazy = graph.hht(surface, graph.signal(surface, "mean_curvature"), emd={"max_imfs": 3})
    (expected,) = graph.compute(lazy, scheduler="synchronous", progress=False)
    assert row.status == "ok" and row.imfs == expected.n_imfs >= 2
    mono = expected.monogenic
    arrays = {"signal": expected.signal, "imfs": expected.imfs, "residue": expected.residue, "riesz": mono.riesz,
              "amplitude": mono.amplitude, "frequency": mono.frequency}
    for folder in ("cli", "api"):
        got = np.load(tmp_path / folder / "x.npz")
        for name, values in arrays.items():
            np.testing.assert_array_equal(got[name], values)


# -- invalid pipelines: a specific message, nothing written ------------------------------------------
GOOD = """\
version: 1
inputs: {mesh}
steps:
  - id: curvature
    op: signal
    params: {{kind: mean_curvature}}
  - id: emd
    op: emd
    params: {{max_imfs: 2}}
outputs:
  folder: {out}
  files:
    - {{from: emd, path: "{{stem}}_imfs.npz"}}
"""

EMD_STEP = "    op: emd\n"
MORE_STEPS = "  - {id: hht, op: hht}\n  - {id: smooth, op: filter_geometry, params: {gain: {kind: constant}}}\noutputs:"

#: case: (edits of GOOD as (old, new) pairs, expected part of the message)
INVALID = {
    "yaml syntax": ([(EMD_STEP, EMD_STEP + "   params: [\n")], "pipeline.yaml:9:4: YAML syntax error"),
    "unknown op": ([("op: emd", "op: emdd")], "unknown op 'emdd'; did you mean 'emd'?"),
    "unknown parameter": ([("max_imfs: 2", "max_imf: 2")],
                          ("pipeline.yaml:9: step 'emd' (op emd): unknown parameter 'max_imf'; did you mean "
                           "'max_imfs'?")),
    "unknown top-level key": ([("steps:", "step:")], "unknown key 'step' in the pipeline; did you mean 'steps'?"),
    "wrong type": ([("max_imfs: 2", "max_imfs: two")],
                   "parameter max_imfs must be an integer in [0, 64]; got 'two' (a string)"),
    "out of range": ([("max_imfs: 2", "ratio: 1.5")], "parameter ratio must be a number in (0.5, 1]; got 1.5"),
    "bad choice": ([("kind: mean_curvature", "kind: mean_curvatur")],
                   "parameter kind must be one of mean_curvature, gaussian_curvature"),
    "missing reference": ([(EMD_STEP, EMD_STEP + "    from: {signal: curvture}\n")],
                          "from.signal refers to unknown step 'curvture'; did you mean 'curvature'?"),
    "reference of the wrong kind": ([(EMD_STEP, EMD_STEP + "    from: {signal: load}\n")],
                                    "from.signal: step 'load' makes surface, but signal needs signal"),
    "cyclic reference": ([("    op: signal\n", "    op: signal\n    from: {surface: smooth}\n"),
                          ("outputs:", MORE_STEPS)],
                         "steps 'curvature' -> 'smooth' -> 'hht' -> 'curvature' form a cycle (each uses the next)"),
    "no earlier input": ([("  - id: curvature\n    op: signal\n    params: {kind: mean_curvature}\n", "")],
                         ("step 'emd' (op emd) needs signal input 'signal', and no earlier step makes one; add a "
                          "step with op filter_signal or signal before it")),
    "duplicate id": ([("id: emd", "id: curvature")], "two steps have the id 'curvature'"),
    "missing input file": ([("inputs: ", "inputs: missing_")], "no such file or folder"),
    "unsupported version": ([("version: 1", "version: 2")],
                            "unsupported pipeline version 2; this hht3d reads version 1"),
    "bad gain": ([("outputs:", MORE_STEPS), ("kind: constant", "kind: band_stop, low: 5, hihg: 9")],
                 "gain band_stop has no parameter 'hihg'; did you mean 'high'?"),
    "output of the wrong kind": ([("_imfs.npz", "_imfs.png")],
                                 "step 'emd' makes emd, which can be written as npz, ply, not 'png'"),
    "unknown output field": ([("outputs:", MORE_STEPS), ('{from: emd, path: "{stem}_imfs.npz"}',
                                                         '{from: hht, path: "{stem}.ply", field: frequncy_1}')],
                             "unknown field 'frequncy_1'"),
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
    with pytest.raises(Exception, match="--set steps.emdd.params.max_imfs=3: steps.emdd matches no list item.*"
                                        "did you mean 'emd'"):
        load_pipeline(path, ["steps.emdd.params.max_imfs=3"])
    with pytest.raises(Exception, match=r"--set steps.emd.params.max_imfs=-1: step 'emd' \(op emd\): parameter "
                                        r"max_imfs must be an integer in \[0, 64\]"):
        load_pipeline(path, ["steps.emd.params.max_imfs=-1"])


# -- runtime errors name the step and the input file -----------------------------------------------------
def test_failed_file_is_reported_with_step_and_file_while_others_finish(tmp_path, folder, capsys):
    (folder / "broken.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n")
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=folder, out=tmp_path / "out"))
    assert _run(path) == 1
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1
    assert f"1 of 3 inputs failed; first: step load failed on {folder / 'broken.ply'}: InputError" in captured.err
    produced = produced_names(tmp_path / "out")
    assert produced == ["part0_imfs.npz", "part1_imfs.npz", "summary.csv", "summary.json"]
    rows = {Path(r["source"]).name: r for r in json.loads((tmp_path / "out" / "summary.json").read_text())}
    assert rows["broken.ply"]["status"] == "failed" and rows["broken.ply"]["step"] == "load"
    assert rows["part1.ply"]["status"] == "ok" and rows["part1.ply"]["imfs"] == 2


def test_failure_inside_a_step_names_that_step(tmp_path, mesh_file, capsys):
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=mesh_file, out=tmp_path / "out").replace("mean_curvature", "luminance"))
    assert _run(path) == 1
    err = capsys.readouterr().err
    assert f"step curvature failed on {mesh_file}: InputError: bumpy: has no vertex colours" in err
    assert not list((tmp_path / "out").glob("*.npz"))


def test_resume_skips_finished_inputs(tmp_path, folder):
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=folder, out=tmp_path / "out"))
    plan = load_pipeline(path)
    run_pipeline(plan, scheduler="synchronous", progress=False)
    (tmp_path / "out" / "part1_imfs.npz").unlink()
    rows = run_pipeline(plan, scheduler="synchronous", progress=False, resume=True)
    assert [r.status for r in rows] == ["skipped", "ok"]


def test_a_worker_killed_mid_write_leaves_no_temporary_file(tmp_path, folder, monkeypatch):
    """A worker killed while writing (a nanny then restarts it, and its task runs again) leaves
    its ``.part`` file behind; the run removes it once every task is done."""
    from hht3d.pipeline import runner

    real, parts = runner.compute, []

    def compute(*args, **kwargs):  # the killed worker's file appears while the run goes on
        parts.append(dead_writers_part(tmp_path / "out", "part1_imfs.npz"))
        return real(*args, **kwargs)

    monkeypatch.setattr(runner, "compute", compute)
    path = tmp_path / "pipeline.yaml"
    path.write_text(GOOD.format(mesh=folder, out=tmp_path / "out"))
    rows = run_pipeline(load_pipeline(path), scheduler="synchronous", progress=False)
    assert [r.status for r in rows] == ["ok", "ok"]
    assert not parts[0].exists() and (tmp_path / "out" / "part1_imfs.npz").is_file()


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
    plan = parse_pipeline("version: 1\ninputs: {builtin: spot}\nsteps: [{op: signal, params: {kind: x}}]\n"
                          "outputs: {files: [{path: a.npz}]}")
    assert plan.inputs[0].name == "spot.ply" and plan.inputs[0].is_file()
    with pytest.raises(Exception, match="unknown builtin model 'spott'; did you mean 'spot'"):
        parse_pipeline("version: 1\ninputs: {builtin: spott}\nsteps: [{op: signal}]\n")


def test_every_operation_and_output_format_runs(tmp_path, mesh_file):
    text = textwrap.dedent(f"""\
        version: 1
        execution: {{scheduler: synchronous, progress: false}}
        inputs: {mesh_file}
        steps:
          - {{id: curvature, op: signal, params: {{kind: mean_curvature}}}}
          - {{id: ensemble, op: eemd, params: {{ensemble_size: 2, max_imfs: 2}}}}
          - {{id: decompose, op: emd, params: {{max_imfs: 2}}}}
          - {{id: hht, op: hht, params: {{max_imfs: 2, ensemble_size: 2}}}}
          - {{id: flat, op: filter_signal, params: {{gain: {{kind: piecewise_linear, points: [[0, 1], [9, 0.5]]}}}}}}
          - {{id: rebuilt, op: reconstruct, params: {{interior_weight: 0.1}}}}
          - {{id: band, op: filter_geometry, from: hht, params: {{gain: {{kind: band_boost, low: 1, high: 9}}}}}}
          - {{id: peaks, op: features, from: {{imfs: decompose}}}}
          - {{id: hks, op: hks_features, from: {{surface: load}}, params: {{eigenpairs: 20}}}}
          - {{id: boosted, op: imf_enhancement, from: {{surface: load, imfs: ensemble}}}}
          - {{id: harmonics, op: manifold_harmonics_filter, from: {{surface: load}},
              params: {{eigenpairs: 20, gain: {{kind: low_pass, cutoff: 3}}}}}}
        outputs:
          folder: {tmp_path / "out"}
          files:
            - {{from: flat, path: flat.npz}}
            - {{from: flat, path: flat.ply, cmap: magma}}
            - {{from: flat, path: flat.png, title: filtered}}
            - {{from: ensemble, path: eemd.npz}}
            - {{from: decompose, path: emd.ply}}
            - {{from: peaks, path: peaks.ply}}
            - {{from: hks, path: hks.npz}}
            - {{from: rebuilt, path: rebuilt.ply}}
            - {{from: band, path: band.png, view: top}}
            - {{from: boosted, path: boosted.ply}}
            - {{from: harmonics, path: harmonics.ply}}
            - {{from: hht, path: amplitude_1.ply, field: amplitude_1}}
            - {{from: hht, path: phase_1.png, figure: field, field: phase_1}}
        """)
    plan = parse_pipeline(text)
    assert {s.op.name for s in plan.steps} == set(OPERATIONS)
    (row,) = run_pipeline(plan)
    assert row.status == "ok", row.error
    assert len(row.outputs) == 13
    out = tmp_path / "out"
    surface = load(mesh_file)
    for path in row.outputs:
        assert_output_fits(Path(path), surface.n_vertices)

    # every file against the same steps run eagerly through the Python API.  EMD, EEMD, features
    # and the HKS are deterministic: exact.  Whatever depends on the Riesz transform sees its
    # shift-group round-off (1e-12 relative) through the gains: 1e-9 of the model size.
    signal = mean_curvature(surface)
    ensemble = eemd(surface, signal, ensemble_size=2, max_imfs=2, seed=0)
    decompose = emd(surface, signal, max_imfs=2)
    result = HHTResult.from_parts(surface, signal, ensemble, monogenic(surface, ensemble.imfs),
                                  {"gradient": "lsq", "method": "quadrature", "tol": 1e-8, "eigenpairs": 300})
    flat = filter_signal(result, PiecewiseLinear([(0, 1), (9, 0.5)]))
    np.testing.assert_array_equal(np.load(out / "eemd.npz")["imfs"], ensemble.imfs)
    np.testing.assert_allclose(np.load(out / "flat.npz")["signal"], flat, rtol=0, atol=1e-9 * np.abs(flat).max())
    np.testing.assert_allclose(load(out / "flat.ply", clean=False).attributes["signal"], flat, rtol=0,
                               atol=1e-9 * np.abs(flat).max())
    emd_fields = load(out / "emd.ply", clean=False).attributes
    for k in range(decompose.n_imfs):
        np.testing.assert_array_equal(emd_fields[f"imf_{k + 1}"], decompose.imfs[k])
    np.testing.assert_array_equal(emd_fields["residue"], decompose.residue)
    peaks = prominent_features(surface, decompose)
    peak_fields = load(out / "peaks.ply", clean=False).attributes
    np.testing.assert_array_equal(np.flatnonzero(peak_fields["feature"]), peaks.vertices)
    np.testing.assert_array_equal(peak_fields["feature_count"], peaks.vertex_counts)
    np.testing.assert_array_equal(np.load(out / "hks.npz")["vertices"], hks_features(surface, eigenpairs=20).vertices)
    expected_surfaces = {
        "rebuilt": reconstruct(surface, flat, interior_weight=0.1),
        "boosted": imf_enhancement(surface, ensemble),
        "harmonics": manifold_harmonics_filter(surface, LowPass(cutoff=3.0), eigenpairs=20),
    }
    for name, expected in expected_surfaces.items():
        written = load(out / f"{name}.ply", clean=False)
        np.testing.assert_array_equal(written.faces, surface.faces)
        np.testing.assert_allclose(written.vertices, expected.vertices, rtol=0, atol=1e-9, err_msg=name)
        assert np.abs(written.vertices - surface.vertices).max() > 1e-4, name  # the step did something
    amplitude = result.monogenic.amplitude[0]
    np.testing.assert_allclose(load(out / "amplitude_1.ply", clean=False).attributes["amplitude_1"], amplitude,
                               rtol=0, atol=1e-12 * amplitude.max())


def _scaled(surface, signal, *, factor: float = 2.0):
    """A made-up core function: the signal times a factor."""
    return factor * np.asarray(signal)


def test_a_new_operation_is_one_core_function_and_one_entry(monkeypatch, tmp_path, mesh_file):
    from hht3d.pipeline import Operation, Param, Slot
    from hht3d.pipeline.params import with_defaults

    monkeypatch.setitem(OPERATIONS, "scaled", Operation(
        "scaled", "the signal times a factor", (Slot("surface", ("surface",)), Slot("signal", ("signal",))),
        "signal", with_defaults(_scaled, Param("factor", "float", "the factor", minimum=0)), func=_scaled))
    text = textwrap.dedent(f"""\
        version: 1
        execution: {{scheduler: synchronous, progress: false}}
        inputs: {mesh_file}
        steps:
          - {{op: signal, params: {{kind: mean_curvature}}}}
          - {{id: tripled, op: scaled, params: {{factor: 3}}}}
        outputs:
          folder: {tmp_path / "out"}
          files: [{{from: tripled, path: tripled.npz}}]
        """)
    plan = parse_pipeline(text)
    assert plan.step("tripled").params == {"factor": 3.0}
    (row,) = run_pipeline(plan)
    assert row.status == "ok", row.error
    np.testing.assert_array_equal(np.load(tmp_path / "out" / "tripled.npz")["signal"],
                                  3.0 * mean_curvature(load(mesh_file)))
    with pytest.raises(Exception, match="parameter factor must be a number >= 0"):
        parse_pipeline(text.replace("factor: 3", "factor: -1"))


def test_inputs_cost_is_announced_and_a_run_that_cannot_fit_is_refused(capsys):
    """validate prints each sized input's estimated peak and time (hht3d.linalg.estimate_hht, the
    plain-install issue's model); with less memory than the estimate, one line refuses before any work."""
    from hht3d import PipelineError, data_path
    from hht3d.linalg import estimate_hht
    from hht3d.pipeline.resources import check_resources, resource_lines

    plan = load_pipeline(data_path("demo.yaml"))
    expected = estimate_hht(2930).describe()
    assert any("spot.ply" in line and expected in line for line in resource_lines(plan))
    with pytest.raises(PipelineError, match=r"spot\.ply: .*needs .* but only .*hht3d\[fast\]"):
        check_resources(plan, available=1)
    assert main(["validate", str(data_path("demo.yaml"))]) == 0
    assert expected in capsys.readouterr().out
