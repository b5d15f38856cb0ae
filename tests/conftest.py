"""Fixtures and markers shared by the tests; helper functions live in tests/helpers/."""

from __future__ import annotations

import os
from pathlib import Path

# Small dense problems run fastest single-threaded; several threads per test
# process oversubscribe this 2-core machine (measured 7x slower eigh).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

# The helpers hold asserts moved out of the tests: pytest shows their operands as in a test.
pytest.register_assert_rewrite("helpers")

from helpers.bad_files import _write_inputs  # noqa: E402
from helpers.meshes import icosphere  # noqa: E402
from helpers.models import shared_model_path  # noqa: E402
from helpers.processes import PIPELINE  # noqa: E402
from hht3d import Surface  # noqa: E402
from hht3d.io import write_ply  # noqa: E402


@pytest.fixture
def shared_model():
    """``get(name)``: path of a model (see :func:`shared_model_path`)."""
    return shared_model_path


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    """The input folder of the bad-input tests (:func:`helpers.bad_files._write_inputs`)."""
    folder = tmp_path_factory.mktemp("bad inputs")  # a space in every input path
    _write_inputs(folder)
    return folder


@pytest.fixture
def job(tmp_path):
    """Four bumpy spheres of 642 vertices and a pipeline writing two files for each into ``out``."""
    scans = tmp_path / "scans"
    scans.mkdir()
    v, f = icosphere(3)
    for k in range(4):
        write_ply(scans / f"s{k}.ply", Surface(v * (1 + 0.05 * np.sin((3 + k) * v[:, [0]])), f))
    (tmp_path / "p.yaml").write_text(PIPELINE.format(inputs=scans, out=tmp_path / "out"))
    return tmp_path


def pytest_collection_modifyitems(items):
    """Mark the tests that read ../shared/data (``shared_data``) or drive chromium (``browser``)."""
    for item in items:
        names = getattr(item, "fixturenames", ())
        if "shared_model" in names:
            item.add_marker(pytest.mark.shared_data)
        if "browser" in names:
            item.add_marker(pytest.mark.browser)
