"""Shared fixtures: analytic meshes and the public models in ../shared/data."""
from __future__ import annotations

import os
import sys
from pathlib import Path

# Small dense problems run fastest single-threaded; several threads per test
# process oversubscribe this 2-core machine (measured 7x slower eigh).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest  # noqa: E402

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
