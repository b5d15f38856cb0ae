"""Option records (hht3d.records): ranges at their ends, records from dicts and overrides, presets."""

import dataclasses

import pytest

from hht3d import InputError, emd
from hht3d.decomposition import PAPER_OPTIONS, EMDOptions, EnsembleOptions
from hht3d.io import LoadOptions
from hht3d.spectral import RieszOptions


@pytest.mark.parametrize(
    "record, name, value, valid",
    [
        (EMDOptions, "ratio", 0.5, False),  # (0.5, 1]: the open end is refused ...
        (EMDOptions, "ratio", 0.5 + 1e-12, True),  # ... just above it is taken
        (EMDOptions, "ratio", 1.0, True),  # the closed end is taken
        (EMDOptions, "ratio", 1.0 + 1e-12, False),
        (EMDOptions, "max_imfs", 0, True),  # [0, 64]
        (EMDOptions, "max_imfs", 64, True),
        (EMDOptions, "max_imfs", 65, False),
        (EMDOptions, "max_imfs", 2.0, False),  # a count is an integer
        (EMDOptions, "max_imfs", True, False),  # not a bool
        (EMDOptions, "cancellation_tolerance", None, True),
        (EMDOptions, "sd_threshold", float("nan"), False),
        (EMDOptions, "envelope", "thin", False),
        (RieszOptions, "tol", 1.0, False),  # [1e-13, 1)
        (RieszOptions, "tol", 1e-13, True),
        (RieszOptions, "tol", 1e-14, False),
        (EnsembleOptions, "ensemble_size", 0, False),
        (LoadOptions, "dimensions", ("intensity", "echo width"), True),  # a non-empty list of names
        (LoadOptions, "dimensions", (), False),
        (LoadOptions, "dimensions", "intensity", False),
        (LoadOptions, "dimensions", ("intensity", 2), False),
        (LoadOptions, "dimensions", ("",), False),
    ],
)
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
    assert LoadOptions.of({"dimensions": ["intensity"]}) == LoadOptions(dimensions=("intensity",))  # lists: tuples
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
    c = emd(
        spot,
        h,
        envelope="biharmonic",
        cancellation_tolerance=None,
        mean_correction=None,
        boundary_extrema=True,
        max_imfs=2,
    )
    assert a.info["options"] == b.info["options"] == c.info["options"]
    np.testing.assert_array_equal(a.imfs, b.imfs)
    np.testing.assert_array_equal(a.imfs, c.imfs)


def _ranged_declarations():
    """``(setting name, module:line)`` of every option(...), Spec(...) and Param(...) call in hht3d/ with a
    minimum= or maximum= keyword; an option or Spec is named by the field or variable it is assigned to,
    a Param by its first argument."""
    import ast
    from pathlib import Path

    import hht3d

    root = Path(hht3d.__file__).parent
    found = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        targets = {}
        for node in ast.walk(tree):
            if isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, ast.Call):
                target = node.targets[0] if isinstance(node, ast.Assign) else node.target
                if isinstance(target, ast.Name):
                    targets[id(node.value)] = target.id
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call) or not {k.arg for k in node.keywords} & {"minimum", "maximum"}:
                continue
            func = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            if func == "Param" and node.args and isinstance(node.args[0], ast.Constant):
                name = node.args[0].value
            elif func in ("option", "Spec"):
                name = targets.get(id(node))
            else:
                continue
            found.append((name, f"{path.relative_to(root.parent)}:{node.lineno}"))
    return found


def test_each_setting_declares_its_range_once():
    """One vocabulary: a setting's range is written in one place; the others read it (option(like=...),
    record_params)."""
    places = {}
    for name, where in _ranged_declarations():
        places.setdefault(name, []).append(where)
    assert len(places) > 20  # the walk finds the declarations
    twice = {name: where for name, where in places.items() if len(where) > 1}
    assert not twice, f"ranges declared more than once: {twice}"


def test_renamed_settings_warn_and_name_the_replacement():
    """RieszOptions.method is RieszOptions.potential; the former name works for one release."""
    with pytest.warns(DeprecationWarning, match="write potential='spectral'"):
        assert RieszOptions.of(method="spectral") == RieszOptions(potential="spectral")
    with pytest.warns(DeprecationWarning), pytest.raises(InputError, match="given as method"):
        RieszOptions.of({"method": "eig"})
    with pytest.warns(DeprecationWarning, match="POTENTIALS"):
        from hht3d.spectral import METHODS
    from hht3d.spectral import POTENTIALS

    assert METHODS == POTENTIALS


def test_a_record_checks_one_setting():
    from hht3d.geometry import SurfaceOptions

    assert SurfaceOptions.check("n_neighbors", 3) == 3
    with pytest.raises(InputError, match=r"n_neighbors must be an integer in \[3, 256\], got 2"):
        SurfaceOptions.check("n_neighbors", 2)
