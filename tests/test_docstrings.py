"""Every public function and class of the API reference has a numpydoc docstring that numpydoc reads.

Each entry of the ``autosummary`` lists of ``docs/api/`` (:func:`test_docs.reference`) that is a
function or a class is parsed with ``numpydoc.docscrape``: it must parse without a warning and
have a summary line.  A function (issue 35) must have a Parameters section when it takes
parameters, a Returns (or Yields) section when its annotation returns something other than
``None``, and an Examples section with a doctest that the suite's ``--doctest-modules`` run of
``hht3d/`` collects from the module defining it.

:data:`WITHOUT_PARAMETERS`, :data:`WITHOUT_RETURNS` and :data:`WITHOUT_EXAMPLES` are ratchets, not
exceptions: a new public function with such a gap fails here, and so does a listed one that
gained its section (remove it from the list).  :data:`NO_EXAMPLE` are the exceptions, each with
its reason.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import warnings

import pytest
from test_docs import reference

docscrape = pytest.importorskip("numpydoc.docscrape", reason="numpydoc comes with the dev and docs extras")

#: Functions whose docstring has no Parameters section yet (issue 35): write it, then drop the name.
WITHOUT_PARAMETERS = frozenset(
    """
    hht3d.pipeline.parse_pipeline
    """.split()
)


#: Functions whose return value is not described in a Returns (or Yields) section yet.
WITHOUT_RETURNS = frozenset(
    """
    hht3d.data_path
    hht3d.graph.mirror
    hht3d.io.data_path
    hht3d.io.load
    hht3d.io.read_npz
    hht3d.io.read_npz_shapes
    hht3d.load
    hht3d.pipeline.builtin_models
    hht3d.pipeline.load_pipeline
    hht3d.pipeline.parse_pipeline
    hht3d.viz.file_html
    hht3d.viz.result_page
    """.split()
)

#: Functions without an Examples section holding a doctest yet.
WITHOUT_EXAMPLES = frozenset(
    """
    hht3d.apps.check_mean_curvature_signal
    hht3d.apps.edit_frequency
    hht3d.apps.features_from_counts
    hht3d.apps.filter_geometry
    hht3d.apps.filter_signal
    hht3d.apps.gains_of
    hht3d.apps.heat_kernel_signature
    hht3d.apps.hks_features
    hht3d.apps.imf_enhancement
    hht3d.apps.manifold_harmonics_filter
    hht3d.apps.prominent_features
    hht3d.apps.reconstruct
    hht3d.apps.reconstruct_from_change
    hht3d.dataset.dataset_graph
    hht3d.dataset.write_summary
    hht3d.decomposition.combine_eemd
    hht3d.decomposition.eemd_member
    hht3d.decomposition.envelope_interpolation
    hht3d.decomposition.envelope_operator
    hht3d.graph.eemd
    hht3d.graph.emd
    hht3d.graph.filter_geometry
    hht3d.graph.filter_signal
    hht3d.graph.hks_features
    hht3d.graph.imf_enhancement
    hht3d.graph.load
    hht3d.graph.manifold_harmonics_filter
    hht3d.graph.mirror
    hht3d.graph.monogenic
    hht3d.graph.monogenic_from_potential
    hht3d.graph.operators
    hht3d.graph.prominent_features
    hht3d.graph.reconstruct
    hht3d.graph.resident
    hht3d.graph.riesz_potential
    hht3d.graph.save
    hht3d.graph.signal
    hht3d.graph.transform
    hht3d.graph.transform_file
    hht3d.io.check_output_paths
    hht3d.io.read_npz
    hht3d.io.read_npz_shapes
    hht3d.io.read_ply_header
    hht3d.linalg.backend_report
    hht3d.linalg.register_backend
    hht3d.linalg.warn_slow_fallback
    hht3d.pipeline.builtin_models
    hht3d.pipeline.failures
    hht3d.pipeline.load_pipeline
    hht3d.pipeline.parse_pipeline
    hht3d.pipeline.pipeline_graph
    hht3d.spectral.combine_quadrature_parts
    hht3d.spectral.instantaneous_frequency
    hht3d.spectral.monogenic_from_potential
    hht3d.spectral.quadrature_nodes
    hht3d.spectral.quadrature_part
    hht3d.spectral.resolution_report
    hht3d.viz.field_figure
    hht3d.viz.file_html
    hht3d.viz.hht_figure
    hht3d.viz.page_html
    hht3d.viz.render_png
    hht3d.viz.result_html
    hht3d.viz.result_page
    hht3d.viz.spectrum_figure
    hht3d.viz.surfaces_html
    hht3d.viz.write_figures
    hht3d.viz.write_page
    """.split()
)

#: Functions whose Example would not be sensible in a doctest, and why.
NO_EXAMPLE = {
    "hht3d.execution.open_client": "starts a Dask LocalCluster of worker processes (or reaches a scheduler)",
    "hht3d.graph.open_client": "the same function as hht3d.execution.open_client",
    "hht3d.execution.share_storage_options": "needs a distributed Client with running workers",
    "hht3d.io.surface_from_pyvista": "needs PyVista, which is not a dependency (tests/io/test_pyvista.py)",
    "hht3d.io.surface_to_pyvista": "needs PyVista, which is not a dependency (tests/io/test_pyvista.py)",
    "hht3d.io.write_las": "needs laspy, the lidar extra (tests/io/test_las.py)",
}


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


def _functions():
    for name, obj in _public():
        if inspect.isfunction(obj):
            yield name, obj, _parsed(obj)[0]


def _check_ratchet(without: set, listed: frozenset, what: str) -> None:
    assert not without - listed, f"no {what}: {sorted(without - listed)}"
    assert not listed - without, f"{what} written now, drop from the list: {sorted(listed - without)}"


def _returns_something(obj) -> bool:
    """Whether the annotation says the function returns a value (``from __future__ import annotations``: text)."""
    return inspect.signature(obj).return_annotation not in ("None", None, inspect.Signature.empty)


def _doctests(obj) -> list[str]:
    """The names of the doctests of ``obj``'s docstring that ``--doctest-modules`` collects from its module."""
    module = inspect.getmodule(obj)
    found = doctest.DocTestFinder().find(module)
    return [t.name for t in found if t.examples and t.name == f"{module.__name__}.{obj.__qualname__}"]


def test_functions_taking_parameters_have_a_parameters_section():
    without = {name for name, obj, doc in _functions() if inspect.signature(obj).parameters and not doc["Parameters"]}
    _check_ratchet(without, WITHOUT_PARAMETERS, "Parameters section")


def test_functions_returning_a_value_have_a_returns_section():
    without = {
        name for name, obj, doc in _functions() if _returns_something(obj) and not (doc["Returns"] or doc["Yields"])
    }
    _check_ratchet(without, WITHOUT_RETURNS, "Returns (or Yields) section")


def test_functions_have_an_example_that_runs_as_a_doctest():
    without = {
        name
        for name, obj, doc in _functions()
        if name not in NO_EXAMPLE and not (any(">>>" in line for line in doc["Examples"]) and _doctests(obj))
    }
    _check_ratchet(without, WITHOUT_EXAMPLES, "Examples section with a doctest")
    public = {name for name, _, _ in _functions()}
    assert not set(NO_EXAMPLE) - public, f"not public functions: {sorted(set(NO_EXAMPLE) - public)}"
    assert not set(NO_EXAMPLE) & WITHOUT_EXAMPLES
