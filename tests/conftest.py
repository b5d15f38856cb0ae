"""Shared fixtures: analytic meshes, the models shipped in the package and those in ../shared/data."""
from __future__ import annotations

import base64
import json
import os
import re
import sys
from importlib import resources
from pathlib import Path

# Small dense problems run fastest single-threaded; several threads per test
# process oversubscribe this 2-core machine (measured 7x slower eigh).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))

#: Public models beside the repository (see ../shared/data/MANIFEST.md).
DATA_DIR = Path(__file__).resolve().parents[1].parent / "shared" / "data"
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


@pytest.fixture
def shared_model():
    """``get(name)``: path of a model (see :func:`shared_model_path`)."""
    return shared_model_path


def assert_same_hht(arrays, expected) -> None:
    """The arrays of a saved HHT result (an ``.npz`` or a dict) equal an in-memory :class:`HHTResult`.

    The decomposition runs the same deterministic code on both sides: exact.  The Riesz transform
    may be summed in shift groups on one side: its round-off, 1e-12 of the largest value.  The
    frequency divides by a² = f² + q², which amplifies that round-off by up to (max a / a)²:
    compared where a > 1e-3 max a (a 1e6 amplification), to 1e-9 relative.
    """
    import numpy as np

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
    import numpy as np

    k = sum(1 for key in attributes if key.startswith("imf_"))
    arrays = {"signal": attributes["signal"], "residue": attributes["residue"]}
    for name, stem in (("imfs", "imf"), ("amplitude", "amplitude"), ("phase", "phase"), ("frequency", "frequency")):
        arrays[name] = np.array([attributes[f"{stem}_{i + 1}"] for i in range(k)]).reshape(k, -1)
    return arrays


def assert_red_blue_swapped(image, flipped, changed=None) -> "np.ndarray":
    """Two RGB renderings (0-255) of a field f and of −f with the same symmetric diverging colour
    scale: wherever they differ by more than 60 levels (or on the given mask), red and blue swap
    (the sign of red − blue flips at ≥ 95% of those pixels).  Returns the mask used."""
    import numpy as np

    if changed is None:
        changed = np.abs(image - flipped).max(axis=2) > 60
    warm = image[..., 0] - image[..., 2]
    cool = flipped[..., 0] - flipped[..., 2]
    assert changed.any()
    assert np.mean(np.sign(warm[changed]) == -np.sign(cool[changed])) > 0.95
    return changed


def page_data(path) -> dict:
    """The JSON the page's script reads."""
    text = path.read_text(encoding="utf-8")
    match = re.search(r'<script type="application/json" id="hht3d-data">(.*?)</script>', text, re.S)
    return json.loads(match.group(1))


def decoded(spec) -> np.ndarray:
    assert spec["dtype"] == "f4"
    return np.frombuffer(base64.b64decode(spec["bdata"]), dtype="<f4")


def field_values(data: dict, name: str, copy: int = 0) -> np.ndarray:
    return decoded(next(f for f in data["fields"] if f["name"] == name)["values"][copy])


def produced_names(folder) -> list[str]:
    """Names in ``folder`` except the manifest and lock hht3d keeps in every output folder (temporaries stay)."""
    from hht3d.io.manifest import LOCK, MANIFEST

    return sorted(p.name for p in Path(folder).iterdir() if p.name not in (MANIFEST, LOCK))
