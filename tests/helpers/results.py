"""Comparisons of saved HHT results with in-memory ones."""

from __future__ import annotations

import numpy as np


def assert_same_hht(arrays, expected) -> None:
    """The arrays of a saved HHT result (an ``.npz`` or a dict) equal an in-memory :class:`HHTResult`.

    The decomposition runs the same deterministic code on both sides: exact.  The Riesz transform
    may be summed in shift groups on one side: its round-off, 1e-12 of the largest value.  The
    frequency divides by a² = f² + q², which amplifies that round-off by up to (max a / a)²:
    compared where a > 1e-3 max a (a 1e6 amplification), to 1e-9 relative.
    """
    np.testing.assert_array_equal(arrays["signal"], expected.signal)
    np.testing.assert_array_equal(arrays["imfs"], expected.imfs)
    np.testing.assert_array_equal(arrays["residue"], expected.residue)
    mono = expected.monogenic
    for name in ("riesz", "amplitude", "phase"):
        if name not in arrays:  # a PLY has no Riesz vectors
            continue
        reference = getattr(mono, name)
        np.testing.assert_allclose(arrays[name], reference, rtol=0, atol=1e-12 * np.abs(reference).max())
    strong = mono.amplitude > 1e-3 * mono.amplitude.max(axis=1, keepdims=True)
    np.testing.assert_allclose(np.asarray(arrays["frequency"])[strong], mono.frequency[strong], rtol=1e-9)


def hht_arrays_from_ply(attributes: dict) -> dict:
    """The per-vertex properties of an HHT result's PLY (``imf_1``, ...) stacked as in its ``.npz``."""
    k = sum(1 for key in attributes if key.startswith("imf_"))
    arrays = {"signal": attributes["signal"], "residue": attributes["residue"]}
    for name, stem in (("imfs", "imf"), ("amplitude", "amplitude"), ("phase", "phase"), ("frequency", "frequency")):
        arrays[name] = np.array([attributes[f"{stem}_{i + 1}"] for i in range(k)]).reshape(k, -1)
    return arrays
