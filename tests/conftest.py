"""Fixtures and markers shared by the tests; helper functions live in tests/helpers/."""
from __future__ import annotations

import os

# Small dense problems run fastest single-threaded; several threads per test
# process oversubscribe this 2-core machine (measured 7x slower eigh).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest  # noqa: E402

from helpers.models import shared_model_path  # noqa: E402


@pytest.fixture
def shared_model():
    """``get(name)``: path of a model (see :func:`shared_model_path`)."""
    return shared_model_path


def pytest_collection_modifyitems(items):
    """Mark the tests that read ../shared/data (``shared_data``) or drive chromium (``browser``)."""
    for item in items:
        names = getattr(item, "fixturenames", ())
        if "shared_model" in names:
            item.add_marker(pytest.mark.shared_data)
        if "browser" in names:
            item.add_marker(pytest.mark.browser)
