"""Every public function and class of the API reference has a numpydoc docstring that numpydoc reads.

Each entry of the ``autosummary`` lists of ``docs/api/`` (:func:`test_docs.reference`) that is a
function or a class is parsed with ``numpydoc.docscrape``: it must parse without a warning and
have a summary line, and a function that takes parameters must have a Parameters section.

:data:`WITHOUT_PARAMETERS` are the functions that still describe their parameters in prose:
a ratchet, not exceptions — a new public function without a Parameters section fails here, and so
does a listed one that gained its section (remove it from the list).
"""

from __future__ import annotations

import importlib
import inspect
import warnings

import pytest
from test_docs import reference

docscrape = pytest.importorskip("numpydoc.docscrape", reason="numpydoc comes with the dev and docs extras")

#: Functions whose docstring has no Parameters section yet (issue 35): write it, then drop the name.
WITHOUT_PARAMETERS = frozenset(
    """
    hht3d.apps.automatic_weight
    hht3d.apps.check_mean_curvature_signal
    hht3d.apps.edit_frequency
    hht3d.apps.gains_of
    hht3d.apps.make_gain
    hht3d.apps.position_weights
    hht3d.apps.repeatability
    hht3d.dataset.output_paths
    hht3d.dataset.write_summary
    hht3d.decomposition.extrema_spacing
    hht3d.decomposition.start_tension
    hht3d.execution.open_client
    hht3d.execution.share_storage_options
    hht3d.geometry.as_imfs
    hht3d.geometry.as_signals
    hht3d.geometry.centroid_distance
    hht3d.geometry.check_signal
    hht3d.geometry.check_signal_path
    hht3d.geometry.check_surface
    hht3d.geometry.coordinate
    hht3d.geometry.estimate_point_normals
    hht3d.geometry.gaussian_curvature
    hht3d.geometry.load_signal
    hht3d.geometry.luminance
    hht3d.geometry.principal_axes
    hht3d.geometry.signal
    hht3d.geometry.stored
    hht3d.geometry.unreliable_vertices
    hht3d.graph.as_key
    hht3d.graph.from_surface
    hht3d.graph.hht
    hht3d.graph.monogenic
    hht3d.graph.open_client
    hht3d.graph.operators
    hht3d.graph.resident
    hht3d.graph.riesz_potential
    hht3d.graph.save
    hht3d.graph.signal
    hht3d.graph.transform
    hht3d.graph.transform_file
    hht3d.io.atomic_path
    hht3d.io.check_name
    hht3d.io.check_output_location
    hht3d.io.check_output_paths
    hht3d.io.check_overwrites
    hht3d.io.check_regular_file
    hht3d.io.confined
    hht3d.io.estimate_point_normals
    hht3d.io.field_colors
    hht3d.io.is_recorded
    hht3d.io.read_npz
    hht3d.io.read_npz_shapes
    hht3d.io.read_ply_header
    hht3d.io.record
    hht3d.io.remove_stale_parts
    hht3d.io.resolve_inputs
    hht3d.io.surface_from_open3d
    hht3d.io.surface_to_open3d
    hht3d.io.write_colored_ply
    hht3d.io.write_npz
    hht3d.io.write_ply
    hht3d.linalg.backend_estimates
    hht3d.linalg.check_backend
    hht3d.linalg.check_memory
    hht3d.linalg.estimate_lines
    hht3d.linalg.factorize
    hht3d.linalg.register_backend
    hht3d.linalg.slow_fallback
    hht3d.linalg.warn_slow_fallback
    hht3d.pipeline.apply_overrides
    hht3d.pipeline.failures
    hht3d.pipeline.parse_pipeline
    hht3d.pipeline.run_pipeline
    hht3d.spectral.combine_quadrature_parts
    hht3d.spectral.dense_eigenpairs
    hht3d.spectral.quadrature_plan
    hht3d.spectral.resolvable_frequency
    hht3d.spectral.smallest_eigenpairs
    hht3d.spectral.vertex_gradient
    hht3d.viz.color_limits
    hht3d.viz.read_fields
    hht3d.viz.render_png
    hht3d.viz.result_html
    hht3d.viz.save_figure
    hht3d.viz.shown_copy
    hht3d.viz.surfaces_html
    hht3d.viz.write_page
    """.split()
)


def _public():
    for package, names in reference().items():
        module = importlib.import_module(package)
        for name in names:
            obj = getattr(module, name)
            if inspect.isfunction(obj) or inspect.isclass(obj):
                yield f"{package}.{name}", obj


def _parsed(obj):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        doc = (
            docscrape.ClassDoc(obj, config={"show_class_members": False})
            if inspect.isclass(obj)
            else docscrape.FunctionDoc(obj)
        )
    return doc, [str(w.message) for w in caught]


def test_every_public_function_and_class_has_a_summary_line():
    missing = []
    for name, obj in _public():
        doc, problems = _parsed(obj)
        if problems or not "".join(doc["Summary"]).strip():
            missing.append((name, problems or "no summary line"))
    assert not missing, missing


def test_functions_taking_parameters_have_a_parameters_section():
    without = {
        name
        for name, obj in _public()
        if inspect.isfunction(obj) and inspect.signature(obj).parameters and not _parsed(obj)[0]["Parameters"]
    }
    assert not without - WITHOUT_PARAMETERS, f"no Parameters section: {sorted(without - WITHOUT_PARAMETERS)}"
    assert not WITHOUT_PARAMETERS - without, (
        f"documented now, drop from the list: {sorted(WITHOUT_PARAMETERS - without)}"
    )
