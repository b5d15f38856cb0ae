"""The input folder of the bad-input tests (tests/cli/test_bad_*.py): good, odd and broken meshes and point
clouds, signal files, a pipeline that is not UTF-8, files that refer to others."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
from plyfile import PlyData, PlyElement

from helpers.meshes import grid, icosphere


# -- input files ----------------------------------------------------------------------------------------------
def _ply(path: Path, vertices, faces=None, *, index="i4", byte_order="<", text=False) -> None:
    """A PLY with float64 x, y, z and (optionally) a ``vertex_indices`` list of ``index`` integers."""
    vertex = np.empty(len(vertices), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    vertex["x"], vertex["y"], vertex["z"] = np.asarray(vertices, dtype=np.float64).T
    elements = [PlyElement.describe(vertex, "vertex")]
    if faces is not None:
        face = np.empty(len(faces), dtype=[("vertex_indices", "O")])
        face["vertex_indices"] = [np.asarray(f, dtype=index) for f in faces]
        kinds = {"i1": "int8", "u1": "uint8", "i4": "int32", "u4": "uint32"}
        elements.append(PlyElement.describe(face, "face", val_types={"vertex_indices": kinds[index]}))
    PlyData(elements, text=text, byte_order=byte_order).write(str(path))


def _bumpy(subdivisions=2):
    v, f = icosphere(subdivisions)
    return v * (1 + 0.06 * np.sin(5 * v[:, [0]])), f


def _plane(z=0.0):
    v, f = grid(8, 8)
    v[:, 2] = z
    return v, f


def _quads():
    """An 8 x 8 grid, wavy in z, as quads with every third cell split into two triangles."""
    v, _ = grid(8, 8)
    v[:, 2] = 0.1 * np.sin(3 * v[:, 0])
    index = np.arange(64).reshape(8, 8)
    faces = []
    for i in range(7):
        for j in range(7):
            q = [index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]]
            faces += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] if (i + j) % 3 == 0 else [q]
    return v, faces


def _cloud(n=400, thickness=0.0, tilt=False):
    rng = np.random.default_rng(0)
    points = np.c_[rng.uniform(size=(n, 2)), thickness * rng.normal(size=n)]
    return points @ np.linalg.qr(rng.normal(size=(3, 3)))[0].T if tilt else points


def _write_inputs(folder: Path) -> None:
    v, f = _bumpy()
    n = len(v)
    _ply(folder / "good.ply", v, f)
    _ply(folder / "huge.ply", 1e30 * v, f)
    _ply(folder / "tiny.ply", 1e-30 * v, f)
    _ply(folder / "big_endian.ply", v, f, byte_order=">")
    _ply(folder / "ascii.ply", v, f, text=True)
    _ply(folder / "uint32.ply", v, f, index="u4")
    small_v, small_f = icosphere(1)
    _ply(folder / "int8.ply", small_v * (1 + 0.05 * np.sin(4 * small_v[:, [0]])), small_f, index="i1")
    _ply(folder / "mixed.ply", *_quads())
    _ply(folder / "non_manifold.ply", np.vstack([v, [[3.0, 3.0, 3.0]]]), np.vstack([f, [[f[0, 0], f[0, 1], n]]]))
    _ply(
        folder / "zero_area.ply",
        np.vstack([v, [[5.0, 0, 0], [6, 0, 0], [7, 0, 0], [8, 0, 0]]]),
        np.vstack([f, [[n, n + 1, n + 2], [n + 1, n + 2, n + 3]]]),
    )
    _ply(folder / "two_parts.ply", np.vstack([v, v + [3.0, 0, 0]]), np.vstack([f, f + n]))
    nan = v.copy()
    nan[5, 1] = np.nan
    _ply(folder / "nan.ply", nan, f)
    infinite = v.copy()
    infinite[7, 2] = np.inf
    _ply(folder / "infinite.ply", infinite, f)
    _ply(folder / "three.ply", np.eye(3), [[0, 1, 2]])
    _ply(folder / "same_point.ply", np.zeros((10, 3)))
    _ply(folder / "bad_index.ply", v, [[0, 1, 2], [0, 1, 500]])
    _ply(folder / "all_degenerate.ply", v, [[0, 0, 1], [1, 1, 2]])
    _ply(folder / "flat_cloud.ply", _cloud())
    _ply(folder / "tilted_cloud.ply", _cloud(tilt=True))
    _ply(folder / "nearly_flat_cloud.ply", _cloud(thickness=1e-12))
    _ply(folder / "line_cloud.ply", np.c_[np.arange(50.0), 2 * np.arange(50.0), np.zeros(50)])
    _ply(folder / "plane_at_2.ply", *_plane(2.0))
    (folder / "empty.ply").write_bytes(b"")
    (folder / "empty.xyz").write_text("")
    good = (folder / "good.ply").read_bytes()
    (folder / "truncated.ply").write_bytes(good[: len(good) // 2])
    (folder / "garbage.obj").write_text("hello world\nv 1 2\nf 1 2 3\n")
    np.savetxt(folder / "ten.xyz", np.random.default_rng(1).normal(size=(10, 3)))
    (folder / "notes.txt").write_text("not a mesh\n")
    np.save(folder / "complex.npy", np.arange(n) + 1j)
    np.savetxt(folder / "signal.csv", np.arange(n))
    np.save(folder / "objects.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    np.save(folder / "short.npy", np.arange(5.0))
    spike = 0.01 * np.sin(5 * v[:, 1])
    spike[17] = 100.0
    np.save(folder / "spike.npy", spike)
    unicode = folder / "dossier é ü" / "modèle 3d"
    unicode.mkdir(parents=True)
    shutil.copy(folder / "good.ply", unicode / "tête à claque.ply")
    (folder / "no_meshes").mkdir()
    (folder / "latin1.yaml").write_bytes("version: 1\nname: caf\xe9\n".encode("latin-1"))
    _write_references(folder, v, f)
    _ply_with_property(folder / "0bad.ply", v, f, "0bad", v[:, 0])
    _ply(folder / "huge300.ply", 1e300 * v, f)
    _ply(folder / "huge70.ply", 1e70 * v, f)
    (folder / "fake.npz").write_bytes(b"PK\x03\x04 this is not a zip archive")


def _gltf(vertices, faces, buffer_uri: str | None = None) -> dict:
    """A glTF 2.0 document of one triangle mesh; its buffer is a data URI unless ``buffer_uri`` is given."""
    import base64

    positions = np.asarray(vertices, dtype="<f4").tobytes()
    indices = np.asarray(faces, dtype="<u4").tobytes()
    data = positions + indices
    uri = buffer_uri or "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    lo, hi = np.min(vertices, axis=0).tolist(), np.max(vertices, axis=0).tolist()
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "buffers": [{"uri": uri, "byteLength": len(data)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(positions), "target": 34962},
            {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices), "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(vertices), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": 3 * len(faces), "type": "SCALAR"},
        ],
    }


def _write_references(folder: Path, v, f) -> None:
    """glTF and OBJ files that refer to other files: beside them (fine) or outside their folder (refused)."""
    (folder / "embedded.gltf").write_text(json.dumps(_gltf(v, f)))
    (folder / "passwd.gltf").write_text(json.dumps(_gltf(v, f, "../../../../../../../../etc/passwd")))
    (folder / "absolute.gltf").write_text(json.dumps(_gltf(v, f, "/etc/passwd")))
    obj = "".join(f"v {a} {b} {c}\n" for a, b, c in v) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
    (folder / "mtl_outside.obj").write_text("mtllib ../../../../../../etc/passwd\n" + obj)


def _ply_with_property(path: Path, v, f, name: str, values) -> None:
    """A PLY whose vertices carry one extra float property ``name`` (any name PLY allows)."""
    vertex = np.empty(len(v), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), (name, "f8")])
    vertex["x"], vertex["y"], vertex["z"] = np.asarray(v).T
    vertex[name] = values
    face = np.empty(len(f), dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = f
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(str(path))
