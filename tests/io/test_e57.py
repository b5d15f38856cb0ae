"""E57 (hht3d.io.e57): a two-scan file written by pye57, each scan with its pose, read as one scan or
all merged; the oracle is each scan's points put through its pose by numpy."""

import numpy as np
import pytest

from hht3d import load
from hht3d.errors import InputError

pye57 = pytest.importorskip("pye57")

QUARTER_TURN = np.array([np.sqrt(0.5), 0, 0, np.sqrt(0.5)])  # quaternion (w, x, y, z): 90 degrees about z
ROTATION = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
TRANSLATIONS = [np.array([512_000.0, 5_400_000.0, 250.0]), np.array([512_030.0, 5_400_010.0, 251.0])]


@pytest.fixture
def scans(tmp_path):
    """Two wavy patches of 300 points in scanner frames, with intensity and colours."""
    rng = np.random.default_rng(0)
    written = []
    e57 = pye57.E57(str(tmp_path / "site.e57"), mode="w")
    for translation in TRANSLATIONS:
        u, v = rng.uniform(0, 10, (2, 300))
        local = np.column_stack([u, v, np.sin(u) * np.cos(v)])
        rgb = rng.integers(0, 256, (300, 3)).astype(np.uint8)
        intensity = rng.uniform(0, 1, 300).astype(np.float32)
        data = {"cartesianX": local[:, 0], "cartesianY": local[:, 1], "cartesianZ": local[:, 2], "intensity": intensity}
        data.update(colorRed=rgb[:, 0], colorGreen=rgb[:, 1], colorBlue=rgb[:, 2])
        e57.write_scan_raw(data, rotation=QUARTER_TURN, translation=translation)
        written.append((local @ ROTATION.T + translation, intensity, rgb))
    e57.close()
    return tmp_path / "site.e57", written


def test_all_scans_merge_with_their_poses(scans):
    path, written = scans
    surface = load(path, clean=False)
    expected = np.vstack([w[0] for w in written])
    assert surface.n_vertices == 600 and np.abs(surface.vertices).max() < 100  # near the local origin
    assert surface.name == "site"  # the file's stem, whatever load options are checked
    np.testing.assert_allclose(surface.vertices + surface.origin, expected, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(surface.attributes["scan"], np.repeat([0.0, 1.0], 300))
    np.testing.assert_array_equal(surface.attributes["intensity"], np.concatenate([w[1] for w in written]))
    np.testing.assert_array_equal(surface.colors * 255, np.vstack([w[2] for w in written]))


def test_one_scan(scans):
    path, written = scans
    surface = load(path, clean=False, scan=1)
    assert surface.n_vertices == 300 and "scan" not in surface.attributes
    np.testing.assert_allclose(surface.vertices + surface.origin, written[1][0], rtol=0, atol=1e-6)


def test_clear_errors(scans, tmp_path, monkeypatch):
    path, _ = scans
    with pytest.raises(InputError, match=r"load option scan is 2, but the file holds 2 scans \(0-based\)"):
        load(path, scan=2)
    monkeypatch.setattr("hht3d.linalg.estimate.available_memory", lambda: 1000)  # as if 10^12 points were declared
    with pytest.raises(InputError, match=r"its scans declare 600 points, which need 0.0 GiB to read; 0.0 GiB are"):
        load(path)
    (tmp_path / "junk.e57").write_bytes(b"ASTM-E57" + bytes(2000))
    with pytest.raises(InputError, match="junk.e57: not a readable E57 file"):
        load(tmp_path / "junk.e57")
