"""References of glTF, OBJ and MTL files checked as the readers take them (hht3d.io.references).

Each case holds a reference that a URL parser or a one-word split would read as harmless but
that Open3D's readers (tinygltf, tinyobjloader) follow outside the scan's folder: a query, a
fragment, backslashes, a file name with a space.  A FIFO waits outside, which a reader opening
it would hang on; the check must refuse without opening it.
"""

from __future__ import annotations

import base64
import json
import os

import pytest

from hht3d.errors import InputError
from hht3d.io.references import check_references

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="the FIFO that a reader would hang on is POSIX's")


@pytest.fixture
def folders(tmp_path):
    """``(scan folder, outside folder)``, the outside one holding a FIFO and a readable file."""
    inside, outside = tmp_path / "scans" / "deep", tmp_path / "outside"
    inside.mkdir(parents=True)
    outside.mkdir()
    os.mkfifo(outside / "x.bin")
    (outside / "evil.mtl").write_text("map_Kd ../outside/x.bin\n")
    (inside / "inside.bin").write_bytes(b"\0" * 12)
    return inside, outside


def _gltf(folder, uri):
    path = folder / "scan.gltf"
    path.write_text(json.dumps({"asset": {"version": "2.0"}, "buffers": [{"uri": uri, "byteLength": 12}]}))
    return path


@pytest.mark.parametrize(
    "uri",
    [
        "inside.bin?/../../../outside/x.bin",
        "inside.bin#/../../../outside/x.bin",
        "..%2F..%2Foutside%2Fx.bin",
        "..\\..\\outside\\x.bin",
    ],
)
def test_a_gltf_uri_that_readers_follow_outside_is_refused(folders, uri):
    inside, _ = folders
    with pytest.raises(InputError, match="refers to"):
        check_references(_gltf(inside, uri))


def test_plain_and_embedded_gltf_uris_stay_accepted(folders):
    inside, _ = folders
    check_references(_gltf(inside, "inside.bin"))
    check_references(_gltf(inside, "data:application/octet-stream;base64," + base64.b64encode(b"\0" * 12).decode()))


@pytest.mark.parametrize(
    "obj, mtl",
    [
        ("mtllib ..\\..\\outside\\evil.mtl\n", None),
        ("mtllib local.mtl\n", "newmtl m\nmap_Kd ../../outside/a b.png\n"),
        ("mtllib local.mtl\n", "newmtl m\nmap_Kd -s 1 1 1 ../../outside/x.bin\n"),
    ],
)
def test_obj_and_mtl_names_are_checked_as_every_reading(folders, obj, mtl):
    """Backslashes are a path on Windows; a texture name may hold spaces, after options."""
    inside, outside = folders
    os.mkfifo(outside / "a b.png")
    (inside / "scan.obj").write_text(obj + "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    if mtl is not None:
        (inside / "local.mtl").write_text(mtl)
    with pytest.raises(InputError, match="refers to"):
        check_references(inside / "scan.obj")
