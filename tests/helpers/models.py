"""Paths of the test models: those shipped in the package and the public ones in ../shared/data."""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

import pytest

#: Public models beside the repository (see ../shared/data/MANIFEST.md).
DATA_DIR = Path(__file__).resolve().parents[2].parent / "shared" / "data"
#: Models the package ships in hht3d/data/: tests load them from there and never skip.
SHIPPED_MODELS = ("spot.ply", "sphere_oct4098.ply")
#: With HHT3D_REQUIRE_DATA=1 (set by .ci/run) a missing ../shared/data model fails the test
#: instead of skipping it: CI always has ../shared/data, so a skip there would hide a lost test.
REQUIRE_DATA = os.environ.get("HHT3D_REQUIRE_DATA", "") not in ("", "0")


def shipped_model_path(name: str) -> Path:
    """Path of a model shipped in the installed package (hht3d/data/)."""
    if name not in SHIPPED_MODELS:
        raise ValueError(f"{name} is not shipped in hht3d/data/; use the shared_model fixture")
    path = Path(str(resources.files("hht3d") / "data" / name))
    assert path.is_file(), f"{path} missing: the package must ship it"
    return path


def shared_model_path(name: str) -> Path:
    """Path of a model: the package's copy when shipped, else ../shared/data (skip or fail when absent)."""
    if name in SHIPPED_MODELS:
        return shipped_model_path(name)
    path = DATA_DIR / name
    if not path.is_file():
        message = f"{path} not present (the public test models live in ../shared/data)"
        if REQUIRE_DATA:
            pytest.fail(f"{message}; HHT3D_REQUIRE_DATA is set, so this test may not skip")
        pytest.skip(message)
    return path
