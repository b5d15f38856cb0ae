"""Meshes the benchmarks make: analytic surfaces and igea at 250k-4M vertices.

* :func:`icosphere`, :func:`grid`, :func:`open_cylinder`, :func:`random_bump_sphere` and
  :func:`sliver_sphere`: analytic surfaces built in memory (``(vertices, faces)``), the same as
  ``tests/helpers/meshes.py`` (the tests keep their own copy; benchmarks import nothing from tests/).
* :func:`generate`: igea (134k vertices) decimated and Loop-subdivided to the sizes of
  :data:`SCALING`, written as a float32 PLY like the public models (``bench_hht --parts scaling``,
  ``bench_viewer``).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from benchmarks.common import model_path

#: The one source of the generated sizes, so the signal content stays comparable between them.
SCALING_SOURCE = "igea"
#: name -> (decimated base vertices, Loop levels); vertices after = 4^levels * base - O(1)
#: (8.6m is igea itself, 134,345 vertices, not decimated).
SCALING = {
    "3k": (3_125, 0),
    "6k": (6_250, 0),
    "9k": (9_375, 0),
    "12k": (12_500, 0),
    "25k": (25_000, 0),
    "250k": (62_500, 1),
    "500k": (125_000, 1),
    "1m": (62_500, 2),
    "4m": (62_500, 3),
    "8.6m": (134_345, 3),
    "10m": (39_063, 4),
}
#: Sizes run unless --sizes says otherwise (4m and 10m take a quarter of an hour and more, and most of the memory).
DEFAULT_SIZES = ["250k", "500k", "1m"]


# -- analytic surfaces (as tests/helpers/meshes.py) ----------------------------------------------------


def icosphere(subdivisions: int = 5, radius: float = 1.0):
    """Icosahedron subdivided ``subdivisions`` times, projected on the sphere.

    Returns ``(vertices, faces)``; 5 subdivisions give 10,242 vertices.
    """
    t = (1 + 5**0.5) / 2
    v = np.array(
        [
            [-1, t, 0],
            [1, t, 0],
            [-1, -t, 0],
            [1, -t, 0],
            [0, -1, t],
            [0, 1, t],
            [0, -1, -t],
            [0, 1, -t],
            [t, 0, -1],
            [t, 0, 1],
            [-t, 0, -1],
            [-t, 0, 1],
        ],
        float,
    )
    f = np.array(
        [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ]
    )
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(edges, axis=0, return_inverse=True)
        mid = v[uniq].mean(axis=1)
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = inv.ravel().reshape(3, -1).T + len(v)  # midpoints of edges (01, 12, 20) per face
        v = np.vstack([v, mid])
        a, b, c = f.T
        ab, bc, ca = m.T
        f = np.concatenate([np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]])
    return radius * v, f


def grid(nx: int, ny: int, a: float = 1.0, b: float = 1.0, jitter: float = 0.0, seed: int = 0):
    """Planar triangulated rectangle ``[0, a] x [0, b]`` at z = 0 with alternating diagonals.

    ``jitter`` moves interior vertices by that fraction of the spacing (seeded).
    """
    x, y = np.meshgrid(np.linspace(0, a, nx), np.linspace(0, b, ny), indexing="ij")
    v = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    if jitter:
        rng = np.random.default_rng(seed)
        interior = (x.ravel() > 0) & (x.ravel() < a) & (y.ravel() > 0) & (y.ravel() < b)
        step = np.array([a / (nx - 1), b / (ny - 1)])
        v[interior, :2] += jitter * step * rng.uniform(-1, 1, (interior.sum(), 2))
    idx = np.arange(nx * ny).reshape(nx, ny)
    p, q, r, s = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    flip = ((np.arange(nx - 1)[:, None] + np.arange(ny - 1)[None, :]) % 2).ravel().astype(bool)
    f1 = np.where(flip[:, None], np.c_[p, q, r], np.c_[p, q, s])
    f2 = np.where(flip[:, None], np.c_[p, r, s], np.c_[q, r, s])
    return v, np.concatenate([f1, f2])


def open_cylinder(n_axial: int, n_around: int, length: float = 1.0, radius: float = 1.0):
    """Open cylinder along z: ``n_axial`` rings of ``n_around`` vertices, ``z ∈ [0, length]``.

    Every quad between rings is split along the same diagonal, so all
    triangles are congruent right triangles; vertex ``i * n_around + j`` sits
    on ring ``i`` at angle ``2πj / n_around``.  Returns ``(vertices, faces)``.
    """
    z = np.linspace(0.0, length, n_axial)
    t = 2 * np.pi * np.arange(n_around) / n_around
    zz, tt = np.meshgrid(z, t, indexing="ij")
    v = np.c_[radius * np.cos(tt.ravel()), radius * np.sin(tt.ravel()), zz.ravel()]
    idx = np.arange(n_axial * n_around).reshape(n_axial, n_around)
    nxt = np.roll(idx, -1, axis=1)
    p, q, r, s = idx[:-1].ravel(), idx[1:].ravel(), nxt[1:].ravel(), nxt[:-1].ravel()
    return v, np.concatenate([np.c_[p, s, r], np.c_[p, r, q]])


def random_bump_sphere(subdivisions: int = 5, count: int = 60, seed: int = 7):
    """Unit icosphere with ``count`` random Gaussian bumps along the normal, of two width classes.

    Even-numbered bumps are narrow (angular σ ≈ 0.08, peak 0.5-1% of the radius), odd ones wide
    (σ ≈ 0.25, peak 1-2%), each with a random sign, centre and ±25% width.  Returns
    ``(vertices, faces, narrow, wide)``: the two radial displacement fields, ``vertices =
    clean · (1 + narrow + wide)`` with ``clean`` on the unit sphere.
    """
    rng = np.random.default_rng(seed)
    clean, faces = icosphere(subdivisions)
    centres = rng.normal(size=(count, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    is_narrow = np.arange(count) % 2 == 0
    sigma = np.where(is_narrow, 0.08, 0.25) * rng.uniform(0.8, 1.25, count)
    peak = 0.01 * rng.uniform(0.5, 1.0, count) * np.where(is_narrow, 1.0, 2.0) * rng.choice([-1, 1], count)
    angle = np.arccos(np.clip(clean @ centres.T, -1, 1))
    bumps = np.exp(-(angle**2) / (2 * sigma**2)) * peak
    narrow, wide = bumps[:, is_narrow].sum(axis=1), bumps[:, ~is_narrow].sum(axis=1)
    return clean * (1 + narrow + wide)[:, None], faces, narrow, wide


def sliver_sphere(subdivisions: int = 4, count: int = 200, eps: float = 1e-3, kind: str = "edge", seed: int = 0):
    """Unit icosphere with ``count`` vertices inserted almost on top of existing ones, all on the sphere.

    ``kind="edge"`` splits an edge ``(a, b)`` at ``(1 − eps) a + eps b`` (two needle triangles per
    side); ``kind="corner"`` splits a face ``(a, b, c)`` at ``(1 − 2 eps) a + eps b + eps c`` (a
    vertex of tiny area among needles).  The new vertex is projected onto the sphere, so 2H = 2 and
    K = 1 everywhere.  Returns ``(vertices, faces)``.
    """
    rng = np.random.default_rng(seed)
    vertices, faces = icosphere(subdivisions)
    vertices, faces = list(vertices), faces.copy()
    keep = np.ones(len(faces), dtype=bool)
    edge_faces: dict = {}
    for index, face in enumerate(faces):
        for edge in ((face[0], face[1]), (face[1], face[2]), (face[2], face[0])):
            edge_faces.setdefault(tuple(sorted(edge)), []).append(index)
    added = []
    for index in rng.choice(len(faces), count, replace=False):
        a, b, c = faces[index]
        touched = edge_faces[tuple(sorted((a, b)))] if kind == "edge" else [index]
        if not keep[touched].all():
            continue
        weights = {"edge": ((1 - eps, a), (eps, b)), "corner": ((1 - 2 * eps, a), (eps, b), (eps, c))}[kind]
        point = sum(w * vertices[v] for w, v in weights)
        new = len(vertices)
        vertices.append(point / np.linalg.norm(point))
        keep[touched] = False
        for t in touched:
            x, y, z = faces[t]
            while {x, y} != {a, b} and kind == "edge":  # rotate so that (a, b) is the first edge
                x, y, z = y, z, x
            added += [[x, new, z], [new, y, z]] if kind == "edge" else [[x, y, new], [y, z, new], [z, x, new]]
    return np.array(vertices), np.vstack([faces[keep], np.array(added, dtype=faces.dtype)])


# -- igea at 250k-4M vertices ---------------------------------------------------------------


def generate(size: str, out: Path) -> dict:
    """Decimate igea and Loop-subdivide it (Open3D); write a float32 PLY like the public models."""
    import open3d as o3d
    from plyfile import PlyData, PlyElement

    import hht3d

    base, levels = SCALING[size]
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    start = time.perf_counter()
    source = hht3d.load(model_path(SCALING_SOURCE))
    mesh = o3d.geometry.TriangleMesh(
        o3d.utility.Vector3dVector(source.vertices), o3d.utility.Vector3iVector(source.faces)
    )
    if base < source.n_vertices:
        mesh = mesh.simplify_quadric_decimation(target_number_of_triangles=2 * base - 4)
    base_vertices = len(mesh.vertices)
    mesh = mesh.subdivide_loop(number_of_iterations=levels)
    v = np.asarray(mesh.vertices, dtype=np.float32)
    f = np.asarray(mesh.triangles, dtype=np.int32)
    vertex = np.empty(len(v), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    vertex["x"], vertex["y"], vertex["z"] = v.T
    face = np.empty(len(f), dtype=[("vertex_indices", "i4", (3,))])
    face["vertex_indices"] = f
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".ply.part")
    PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(str(tmp))
    tmp.replace(out)
    return {
        "size": size,
        "source": SCALING_SOURCE,
        "base_vertices": base_vertices,
        "levels": levels,
        "vertices": len(v),
        "faces": len(f),
        "seconds": time.perf_counter() - start,
        "edge_manifold": bool(mesh.is_edge_manifold()),
        "vertex_manifold": bool(mesh.is_vertex_manifold()),
    }


def cloud_of(mesh: Path, out: Path) -> dict:
    """The vertices of a generated mesh as a point cloud PLY (no faces, no normals: hht3d estimates them)."""
    from plyfile import PlyData, PlyElement

    start = time.perf_counter()
    vertex = PlyData.read(str(mesh))["vertex"].data
    tmp = out.with_suffix(".ply.part")
    PlyData([PlyElement.describe(vertex, "vertex")]).write(str(tmp))
    tmp.replace(out)
    return {"source": mesh.name, "vertices": len(vertex), "seconds": time.perf_counter() - start}
