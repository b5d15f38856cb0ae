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
    hht3d.pipeline.parse_pipeline
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
