"""The output formats (hht3d.output_formats): every format of every kind of result written by a pipeline,
each file against the same steps run eagerly through the Python API; a new format is one entry and one writer."""

import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from helpers.meshes import icosphere
from helpers.pipelines import GOOD, assert_output_fits, bumpy_file
from hht3d.apps import (
    LowPass,
    PiecewiseLinear,
    filter_signal,
    hks_features,
    imf_enhancement,
    manifold_harmonics_filter,
    prominent_features,
    reconstruct,
)
from hht3d.cli import main
from hht3d.dataset import dataset_graph
from hht3d.decomposition import eemd, emd
from hht3d.errors import InputError, PipelineError
from hht3d.geometry.signals import mean_curvature
from hht3d.geometry.surface import Surface
from hht3d.io import load
from hht3d.io.atomic import atomic_path
from hht3d.io.write import write_npz
from hht3d.output_formats import FORMATS, Format, FormatOptions, by_suffix, plain_formats
from hht3d.pipeline import OPERATIONS, parse_pipeline, run_pipeline
from hht3d.pipeline.json_schema import pipeline_schema
from hht3d.records import option
from hht3d.spectral.monogenic_signal import monogenic
from hht3d.transform import HHTResult, hht


@pytest.fixture
def mesh_file(tmp_path):
    return bumpy_file(tmp_path / "in")


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
    assert {s.op.name for s in plan.steps} == set(OPERATIONS) - {"python"}  # it runs code: test_python_step.py
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
    result = HHTResult.from_parts(
        surface,
        signal,
        ensemble,
        monogenic(surface, ensemble.imfs),
        {"gradient": "lsq", "method": "quadrature", "tol": 1e-8, "eigenpairs": 300},
    )
    flat = filter_signal(result, PiecewiseLinear([(0, 1), (9, 0.5)]))
    np.testing.assert_array_equal(np.load(out / "eemd.npz")["imfs"], ensemble.imfs)
    np.testing.assert_allclose(np.load(out / "flat.npz")["signal"], flat, rtol=0, atol=1e-9 * np.abs(flat).max())
    np.testing.assert_allclose(
        load(out / "flat.ply", clean=False).attributes["signal"], flat, rtol=0, atol=1e-9 * np.abs(flat).max()
    )
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
    np.testing.assert_allclose(
        load(out / "amplitude_1.ply", clean=False).attributes["amplitude_1"],
        amplitude,
        rtol=0,
        atol=1e-12 * amplitude.max(),
    )


@dataclass(frozen=True)
class _Digits(FormatOptions):
    digits: int = option(6, "significant digits", minimum=1, maximum=17)


def _signal_txt(values, surface, path, *, digits):
    with atomic_path(path) as tmp:
        np.savetxt(tmp, values, fmt=f"%.{digits - 1}e")
    return Path(path)


def _hht_energy(result, surface, path):
    return write_npz(path, {"energy": (result.imfs**2 * result.surface.mass_diagonal).sum(1)})


def test_a_new_format_is_one_entry_and_one_writer(monkeypatch, tmp_path, mesh_file, capsys):
    """Its suffix names it, its options are checked, the JSON Schema and ``hht3d ops`` list it; a format of
    an HHT result without options is one HHTResult.save and run_dataset write too."""
    monkeypatch.setitem(FORMATS["signal"], "txt", Format("txt", ".txt", "the values as text", _signal_txt, _Digits))
    monkeypatch.setitem(FORMATS["hht"], "energy", Format("energy", ".energy", "IMF energies", _hht_energy))
    text = GOOD.format(mesh=mesh_file, out=tmp_path / "out")
    txt = "outputs.files=[{from: curvature, path: '{stem}.txt', digits: %d}]"
    plan = parse_pipeline(text, overrides=["execution={scheduler: synchronous, progress: false}", txt % 3])
    assert (plan.outputs[0].format.name, plan.outputs[0].options) == ("txt", {"digits": 3})
    with pytest.raises(PipelineError, match=r"parameter digits must be an integer in \[1, 17\]"):
        parse_pipeline(text, overrides=[txt % 0])
    (row,) = run_pipeline(plan)
    assert row.status == "ok", row.error
    expected = mean_curvature(load(mesh_file))
    np.testing.assert_allclose(np.loadtxt(tmp_path / "out" / "bumpy.txt"), expected, rtol=1e-2)

    output = pipeline_schema()["$defs"]["output"]["properties"]
    assert {"txt", "energy"} <= set(output["format"]["enum"]) and output["digits"]["maximum"] == 17
    assert main(["ops"]) == 0
    assert "signal    txt          the values as text [digits=6]" in capsys.readouterr().out

    assert list(plain_formats("hht")) == [".ply", ".npz", ".vtu", ".vtp", ".energy"]
    assert by_suffix()[".energy"] == "energy"
    surface = Surface(*icosphere(2))
    result = hht(surface, surface.vertices[:, 0], max_imfs=1)
    with np.load(result.save(tmp_path / "x.energy"), allow_pickle=False) as saved:
        np.testing.assert_allclose(saved["energy"], (result.imfs**2 * surface.mass_diagonal).sum(1))
    dataset_graph([mesh_file], tmp_path / "dataset", formats=(".energy",), max_imfs=1)  # accepted


def test_format_options_refuse_what_the_types_cannot_say():
    """A field no HHT result has and a colour map Matplotlib does not know, named with the fields
    :meth:`HHTResult.vertex_attributes` makes."""
    options = FORMATS["hht"]["colored_ply"].options
    assert options.of(field="frequency_12").field == "frequency_12"
    for field in ("imf_0", "frequncy_1", "amplitude_01", "imf_", "residue_1"):
        with pytest.raises(
            InputError,
            match=r"unknown field .*; use signal, residue, imf_K, amplitude_K, "
            r"phase_K or frequency_K",
        ):
            options.of(field=field)
    with pytest.raises(InputError, match="unknown colour map 'viridi'; did you mean 'viridis'"):
        options.of(cmap="viridi")
    assert FORMATS["signal"]["png"].options.of().cmap is None  # the automatic colour map
