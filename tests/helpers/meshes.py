"""Analytic test surfaces shared by the tests (built here, no data files needed)."""

from __future__ import annotations

import numpy as np


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


def bumpy_sphere(subdivisions: int = 2, waves: int = 5, scale: float = 1.0):
    """An icosphere with a smooth bump pattern: ``(vertices, faces)``."""
    v, f = icosphere(subdivisions)
    return scale * v * (1 + 0.06 * np.sin(waves * v[:, [0]]) * np.cos(4 * v[:, [1]])), f


def fibonacci_sphere(n: int, radius: float = 1.0):
    """``n`` nearly uniform points on a sphere (Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = np.pi * (1 + 5**0.5) * i
    r = np.sqrt(1 - z**2)
    return radius * np.c_[r * np.cos(phi), r * np.sin(phi), z]


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


def gltf_to_glb(gltf_path, glb_path):
    """Pack a ``.gltf`` with one embedded (data-URI) buffer into a binary ``.glb``.

    Open3D 0.18–0.20 writes ``.glb`` files its own reader rejects, so the
    GLB test builds one by the glTF 2.0 container rules instead.
    """
    import base64
    import json
    import struct

    doc = json.loads(open(gltf_path).read())
    (buffer,) = doc["buffers"]
    payload = base64.b64decode(buffer.pop("uri").split(",", 1)[1])
    payload += b"\0" * (-len(payload) % 4)
    buffer["byteLength"] = len(payload)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(payload)
    with open(glb_path, "wb") as out:
        out.write(struct.pack("<4sII", b"glTF", 2, total))
        out.write(struct.pack("<I4s", len(text), b"JSON") + text)
        out.write(struct.pack("<I4s", len(payload), b"BIN\0") + payload)


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


def bump_band_sphere(subdivisions: int = 5, waves: int = 20, amplitude: float = 0.005):
    """Unit icosphere carrying a band of ``waves`` bumps around the equator, along the normal.

    The displacement is ``amplitude · cos(waves·φ) · sin^waves(θ)``: the sectoral
    spherical harmonic ``Y_l^l`` (``l = waves``) scaled to a peak of 1, an
    eigenfunction of the sphere's Laplacian with ``λ = l(l+1)``, so the bumps
    have the single scale ``ω = √(l(l+1))`` radians per unit length; it decays
    away from the equator over a polar width of about ``1/√l``.

    Returns ``(vertices, faces, clean_vertices, bumps)`` with ``bumps`` the
    unit-peak pattern and ``clean_vertices`` on the unit sphere.
    """
    clean, faces = icosphere(subdivisions)
    x, y, z = clean.T
    bumps = np.cos(waves * np.arctan2(y, x)) * np.clip(1 - z**2, 0, None) ** (waves / 2)
    return clean * (1 + amplitude * bumps)[:, None], faces, clean, bumps


def height_field_grid(nx: int = 30, ny: int = 30, height: float = 0.15):
    """Open curved patch: :func:`grid` on ``[0, 1]²`` lifted to ``z = height·sin(2πx)·cos(πy)``."""
    v, f = grid(nx, ny)
    v[:, 2] = height * np.sin(2 * np.pi * v[:, 0]) * np.cos(np.pi * v[:, 1])
    return v, f


def disjoint_union(*meshes):
    """Concatenate ``(vertices, faces)`` pairs into one mesh with separate components."""
    vertices, faces, offset = [], [], 0
    for v, f in meshes:
        vertices.append(np.asarray(v, dtype=float))
        faces.append(np.asarray(f) + offset)
        offset += len(v)
    return np.vstack(vertices), np.vstack(faces)


def jittered_height_field(nx: int = 14, ny: int = 11, jitter: float = 0.35, seed: int = 5):
    """:func:`grid` on ``[0, 1]²`` with jittered interior vertices (many obtuse triangles), lifted
    to ``z = 0.2·sin(2πx)·cos(πy)``."""
    v, f = grid(nx, ny, jitter=jitter, seed=seed)
    v[:, 2] = 0.2 * np.sin(2 * np.pi * v[:, 0]) * np.cos(np.pi * v[:, 1])
    return v, f


def reference_operators(vertices, faces):
    """Dense cotan stiffness ``L``, mixed-Voronoi areas ``A`` and unit vertex normals ``N``.

    Written face by face from the textbook formulas (angles by ``arccos``; Meyer et al. 2002
    for the areas; area-weighted face normals), independently of :mod:`hht3d.geometry.operators`, as
    the reference for tests of code that uses the operators.  For small meshes only.
    Returns ``(L (n, n), A (n,), N (n, 3))``.
    """
    v = np.asarray(vertices, dtype=float)
    n = len(v)
    lap, area, normal = np.zeros((n, n)), np.zeros(n), np.zeros((n, 3))
    for tri in np.asarray(faces):
        p = v[tri]
        angle = np.empty(3)
        for k in range(3):
            a, b = p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]
            angle[k] = np.arccos(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1, 1))
        cross = np.cross(p[1] - p[0], p[2] - p[0])
        normal[tri] += cross
        face_area = 0.5 * np.linalg.norm(cross)
        for k in range(3):  # the edge opposite corner k, weight cot(angle_k) / 2
            i, j = tri[(k + 1) % 3], tri[(k + 2) % 3]
            w = 0.5 / np.tan(angle[k])
            lap[i, j] -= w
            lap[j, i] -= w
            lap[i, i] += w
            lap[j, j] += w
        for k in range(3):
            if angle.max() > np.pi / 2:  # obtuse triangle: half to the obtuse corner, a quarter to the others
                area[tri[k]] += face_area / 2 if angle[k] > np.pi / 2 else face_area / 4
            else:  # Voronoi share: the edges k-(k+1) and k-(k+2), opposite the angles at k+2 and k+1
                to_next = np.sum((p[(k + 1) % 3] - p[k]) ** 2) / np.tan(angle[(k + 2) % 3])
                to_prev = np.sum((p[(k + 2) % 3] - p[k]) ** 2) / np.tan(angle[(k + 1) % 3])
                area[tri[k]] += (to_next + to_prev) / 8
    return lap, area, normal / np.linalg.norm(normal, axis=1, keepdims=True)


def boundary_mask(n: int, faces) -> np.ndarray:
    """Vertices on an edge that only one face uses (counted with a plain dictionary)."""
    count: dict = {}
    for tri in np.asarray(faces):
        for k in range(3):
            edge = tuple(sorted((int(tri[k]), int(tri[(k + 1) % 3]))))
            count[edge] = count.get(edge, 0) + 1
    mask = np.zeros(n, dtype=bool)
    for (i, j), c in count.items():
        if c == 1:
            mask[[i, j]] = True
    return mask


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
