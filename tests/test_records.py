"""Option records (hht3d.records): ranges at their ends, records from dicts and overrides, presets."""
import dataclasses

import pytest

from hht3d import InputError, emd
from hht3d.decomposition import PAPER_OPTIONS, EMDOptions, EnsembleOptions
from hht3d.spectral import RieszOptions


@pytest.mark.parametrize("record, name, value, valid", [
    (EMDOptions, "ratio", 0.5, False),            # (0.5, 1]: the open end is refused ...
    (EMDOptions, "ratio", 0.5 + 1e-12, True),     # ... just above it is taken
    (EMDOptions, "ratio", 1.0, True),             # the closed end is taken
    (EMDOptions, "ratio", 1.0 + 1e-12, False),
    (EMDOptions, "max_imfs", 0, True),            # [0, 64]
    (EMDOptions, "max_imfs", 64, True),
    (EMDOptions, "max_imfs", 65, False),
    (EMDOptions, "max_imfs", 2.0, False),         # a count is an integer
    (EMDOptions, "max_imfs", True, False),        # not a bool
    (EMDOptions, "cancellation_tolerance", None, True),
    (EMDOptions, "sd_threshold", float("nan"), False),
    (EMDOptions, "envelope", "thin", False),
    (RieszOptions, "tol", 1.0, False),            # [1e-13, 1)
    (RieszOptions, "tol", 1e-13, True),
    (RieszOptions, "tol", 1e-14, False),
    (EnsembleOptions, "ensemble_size", 0, False),
])
def test_ranges_hold_at_their_ends(record, name, value, valid):
    if valid:
        assert getattr(record.of(**{name: value}), name) == value
    else:
        with pytest.raises(InputError, match=name):
            record.of(**{name: value})


def test_record_dict_and_overrides_give_one_record():
    from_dict = EMDOptions.of({"max_imfs": 3, "tension": 1.0})
    assert from_dict == EMDOptions(max_imfs=3, tension=1.0)
    assert EMDOptions.of(from_dict, max_imfs=4) == EMDOptions(max_imfs=4, tension=1.0)
    assert dataclasses.replace(PAPER_OPTIONS, max_imfs=2).envelope == "biharmonic"
    with pytest.raises(InputError, match="did you mean 'max_imfs'"):
        EMDOptions.of(max_imf=3)
    with pytest.raises(InputError, match="EMDOptions or a dict"):
        EMDOptions.of(["max_imfs"])


def test_emd_takes_a_record_a_dict_or_overrides_alike():
    """The three ways of passing settings decompose identically (same record, same numbers)."""
    import numpy as np

    from hht3d import data_path, load
    from hht3d.geometry.signals import mean_curvature

    spot = load(data_path("spot.ply"))
    h = mean_curvature(spot)
    a = emd(spot, h, PAPER_OPTIONS, max_imfs=2)
    b = emd(spot, h, {**PAPER_OPTIONS.as_dict(), "max_imfs": 2})
    c = emd(spot, h, envelope="biharmonic", cancellation_tolerance=None, mean_correction=None, boundary_extrema=True,
            max_imfs=2)
    assert a.info["options"] == b.info["options"] == c.info["options"]
    np.testing.assert_array_equal(a.imfs, b.imfs)
    np.testing.assert_array_equal(a.imfs, c.imfs)
