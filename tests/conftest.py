"""Shared fixtures: analytic meshes and the public models in ../shared/data."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

#: Public models beside the repository (see ../shared/data/MANIFEST.md).
DATA_DIR = Path(__file__).resolve().parents[1].parent / "shared" / "data"


@pytest.fixture
def shared_model():
    """Path of a model in ../shared/data; skips the test when absent."""

    def get(name: str) -> Path:
        path = DATA_DIR / name
        if not path.is_file():
            pytest.skip(f"{path} not present (the public test models live in ../shared/data)")
        return path

    return get
