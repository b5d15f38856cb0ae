"""Every operation and every output format of a pipeline (hht3d.pipeline.outputs), each file against the same
steps run eagerly through the Python API."""
import textwrap
from pathlib import Path

import numpy as np
from helpers.pipelines import assert_output_fits

from hht3d.apps import (LowPass, PiecewiseLinear, filter_signal, hks_features, imf_enhancement,
                        manifold_harmonics_filter, prominent_features, reconstruct)
from hht3d.decomposition import eemd, emd
from hht3d.transform import HHTResult
from hht3d.io import load
from hht3d.spectral.monogenic_signal import monogenic
from hht3d.geometry.signals import mean_curvature
from hht3d.pipeline import OPERATIONS, parse_pipeline, run_pipeline


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
