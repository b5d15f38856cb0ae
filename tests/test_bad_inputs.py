"""What a new user feeds the ``hht3d`` command, one table row each (issue 15).

Every row is an input (CLI arguments, the pipeline text, the files in the
input folder), the expected fragment of the message, the exit code and the
files that must not exist afterwards.  An error is one ``hht3d: error: ...``
line on stderr with exit code 1; a success prints nothing on stderr (no
Qhull or Open3D chatter, no progress bar in a log) and, where the input is
odd but valid, its row checks the numbers of the result.  After every row no
temporary (``.part``) or probe file is left anywhere.
"""
from __future__ import annotations

import copy
import errno
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers.meshes import grid, icosphere
from dask import delayed
from plyfile import PlyData, PlyElement

from hht3d.cli import main
from hht3d.errors import HHT3DError
from hht3d.io import load
from hht3d.pipeline import OPERATIONS, parse_pipeline
from hht3d.pipeline.schema import EXECUTION
from hht3d.graph.scheduling import compute

ROOT = Path(__file__).resolve().parents[1]

PIPELINE = """\
version: 1
execution: {scheduler: synchronous, progress: false}
inputs: "<in>/good.ply"
steps:
  - {id: curvature, op: signal, params: {kind: mean_curvature}}
  - {id: hht, op: hht, params: {max_imfs: 2, riesz_tasks: 1}}
outputs:
  folder: "<out>"
  summary: false
  files:
    - {from: hht, path: "{stem}_hht.npz"}
"""


def _alias_bomb(levels: int) -> str:
    """A YAML flow list whose last item, once its aliases are expanded, holds ``9**levels`` strings."""
    names = "abcdefghijklmnop"[:levels]
    items = [f"&a [{', '.join(['lol'] * 9)}]"]
    items += [f"&{b} [{', '.join([f'*{a}'] * 9)}]" for a, b in zip(names, names[1:])]
    return f"[{', '.join(items)}]"


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
    _ply(folder / "zero_area.ply", np.vstack([v, [[5.0, 0, 0], [6, 0, 0], [7, 0, 0], [8, 0, 0]]]),
         np.vstack([f, [[n, n + 1, n + 2], [n + 1, n + 2, n + 3]]]))
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
    (folder / "truncated.ply").write_bytes(good[:len(good) // 2])
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
    return {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
            "buffers": [{"uri": uri, "byteLength": len(data)}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(positions), "target": 34962},
                            {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices),
                             "target": 34963}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(vertices), "type": "VEC3",
                           "min": lo, "max": hi},
                          {"bufferView": 1, "componentType": 5125, "count": 3 * len(faces), "type": "SCALAR"}]}


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


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("bad inputs")  # a space in every input path
    _write_inputs(folder)
    return folder


# -- checks of correct results ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Ran:
    """What a row's checks see: the folders, the stdout and the exit code."""

    inputs: Path
    out: Path
    stdout: str


def _npz(ran: Ran, stem: str):
    return np.load(ran.out / f"{stem}_hht.npz")


def _decomposes(result) -> None:
    np.testing.assert_allclose(result["imfs"].sum(axis=0) + result["residue"], result["signal"], atol=1e-12)


def _same_as_good(stem: str, scale: float = 1.0, rtol: float = 1e-9):
    """The result equals that of good.ply with lengths scaled by ``scale`` (curvature and frequency by 1/scale)."""

    def check(ran: Ran) -> None:
        good, other = _npz(ran, "good"), _npz(ran, stem)
        np.testing.assert_allclose(other["vertices"], scale * good["vertices"], rtol=rtol)
        for name in ("signal", "imfs", "frequency"):
            np.testing.assert_allclose(scale * other[name], good[name], rtol=rtol, atol=rtol * np.abs(good[name]).max())
        np.testing.assert_allclose(other["phase"], good["phase"], atol=1e-6)

    return check


def _flat_cloud(ran: Ran) -> None:
    result = _npz(ran, "flat_cloud")
    assert result["imfs"].shape == (0, 400) and np.abs(result["signal"]).max() < 1e-12
    normals = load(ran.inputs / "flat_cloud.ply").normals
    np.testing.assert_allclose(normals, np.tile([0.0, 0.0, 1.0], (400, 1)))


def _nearly_flat(stem: str):
    def check(ran: Ran) -> None:
        result = _npz(ran, stem)
        assert result["signal"].shape == (400,) and np.abs(result["signal"]).max() < 1e-6  # flat: ~no curvature
        _decomposes(result)

    return check


def _constant(ran: Ran) -> None:
    result = _npz(ran, "plane_at_2")
    assert result["imfs"].shape == (0, 64)
    np.testing.assert_array_equal(result["residue"], np.full(64, 2.0))


def _mixed(ran: Ran) -> None:
    result = _npz(ran, "mixed")
    v, faces = _quads()
    assert len(result["faces"]) == sum(len(f) - 2 for f in faces) == 98  # quads fan-triangulated
    np.testing.assert_array_equal(result["vertices"], v)
    _decomposes(result)


def _non_manifold(ran: Ran) -> None:
    result = _npz(ran, "non_manifold")
    assert result["signal"].shape == (163,) and np.all(np.isfinite(result["frequency"]))
    _decomposes(result)


def _zero_area(ran: Ran) -> None:
    result, good = _npz(ran, "zero_area"), _npz(ran, "good")
    np.testing.assert_array_equal(result["vertices"], good["vertices"])  # the flat sliver component is dropped
    np.testing.assert_allclose(result["imfs"], good["imfs"], atol=1e-12)


def _two_parts(ran: Ran) -> None:
    result = _npz(ran, "two_parts")
    half = len(result["signal"]) // 2
    np.testing.assert_allclose(result["signal"][:half], result["signal"][half:], atol=1e-12)
    _decomposes(result)


def _int8(ran: Ran) -> None:
    result = _npz(ran, "int8")
    np.testing.assert_array_equal(result["faces"], icosphere(1)[1])


def _unicode(ran: Ran) -> None:
    (path,) = ran.out.glob("*.npz")
    assert path.name == "tête à claque_hht.npz"
    assert "tête à claque.ply: ok, 162 vertices" in ran.stdout


def _quality_columns(ran: Ran) -> None:
    (row,) = json.loads((ran.out / "summary.json").read_text())
    assert row["energy_ratio"] > 0 and isinstance(row["orthogonality_index"], float)
    header = (ran.out / "summary.csv").read_text().splitlines()[0]
    assert "energy_ratio,orthogonality_index,io_leaking,io_cancelling,warnings" in header
    assert f"energy ratio {row['energy_ratio']:.3g}" in ran.stdout


def _warned(ran: Ran) -> None:
    (row,) = json.loads((ran.out / "summary.json").read_text())
    assert row["status"] == "ok" and any("the signal spikes" in w for w in row["warnings"])
    for warning in row["warnings"]:
        assert f"\n  warning: {warning}\n" in ran.stdout


def _resumed(ran: Ran) -> None:
    (row,) = json.loads((ran.out / "summary.json").read_text())
    assert (row["status"], row["vertices"], row["imfs"], row["seconds"]) == ("skipped", 162, 2, None)
    assert "skipped (outputs complete), 162 vertices, 2 IMFs; not re-run" in ran.stdout


def _partial(ran: Ran) -> None:
    (row,) = json.loads((ran.out / "summary.json").read_text())
    written = str(ran.out / "good_signal.npz")
    assert row["status"] == "failed" and row["outputs"] == [written] and Path(written).is_file()
    assert f"  wrote {written}" in ran.stdout


def _every_line_printed(ran: Ran) -> None:
    assert "good.ply: ok, 162 vertices, 2 IMFs" in ran.stdout and "huge.ply: ok, 162 vertices" in ran.stdout


# -- the table ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Case:
    """One bad input.

    ``argv`` and ``yaml`` (the pipeline, default :data:`PIPELINE`) may use
    ``<in>`` (the input folder), ``<out>`` (the output folder, which does not
    exist before), ``<tmp>`` and ``<pipeline>`` (the pipeline file).
    ``absent`` are paths relative to ``<tmp>`` that must not exist afterwards.
    """

    argv: tuple[str, ...]
    message: str
    code: int = 1
    absent: tuple[str, ...] = ("out",)
    yaml: str = PIPELINE
    check: Callable | None = None
    before: tuple[tuple[str, ...], ...] = ()  # runs made first (--resume)
    fault: Callable | None = None  # fault(monkeypatch) injected before the run
    unprivileged: bool = False  # run without root's permission override (read-only folders)
    issue: bool = False  # a case listed in issue 15 (the rest extend it)
    setup: Callable | None = None  # setup(tmp_path, inputs) after the runs made first: files the user made


def run(*sets: str, command: str = "run") -> tuple[str, ...]:
    """``hht3d COMMAND <pipeline> --set A --set B ...``."""
    return (command, "<pipeline>", *[a for s in sets for a in ("--set", s)])


def validate(*sets: str) -> tuple[str, ...]:
    return run(*sets, command="validate")


def refused(name: str, message: str) -> Case:
    """A run on the input file ``name`` fails with ``message`` and writes nothing."""
    return Case(run(f"inputs=<in>/{name}"), message)


def accepted(*names: str, check: Callable, issue: bool = False) -> Case:
    """A run on the input files ``names`` succeeds, prints nothing on stderr, and ``check`` holds for its results."""
    return Case(run(f"inputs=[{', '.join(f'<in>/{n}' for n in names)}]"), "", 0, (), check=check, issue=issue)


def _no_graph(monkeypatch) -> None:
    """Validation must not build the task graph (10,000 EEMD members took 105 s to build)."""

    def refuse(*args, **kwargs):
        raise AssertionError("validate built the task graph")

    monkeypatch.setattr("hht3d.pipeline.runner.pipeline_graph", refuse)
    monkeypatch.setattr("hht3d.graph.stages.Builder.task", refuse)


def _failing_write(name: str, error: int):
    """A fault: writing the summary file ``name`` fails with ``error`` (ENOSPC: the disk filled up; EACCES:
    the folder stopped being writable), after the run's check of the output locations passed."""
    write_text = pathlib.Path.write_text

    def fail(self, *args, **kwargs):
        if self.name.startswith(f".{name}"):
            raise OSError(error, os.strerror(error))
        return write_text(self, *args, **kwargs)

    return lambda monkeypatch: monkeypatch.setattr(pathlib.Path, "write_text", fail)


TWO_GOOD = 'inputs=["<in>/good.ply", "<in>/huge.ply"]'
SUMMARY = "outputs.summary=true"


# -- issue 23: nothing read or written outside where it belongs ------------------------------------------------
def _user_file(relative: str, content: bytes = b"mine"):
    """A setup: the user's own file at ``<tmp>/relative``."""
    def setup(tmp: Path, inputs: Path) -> None:
        (tmp / relative).parent.mkdir(parents=True, exist_ok=True)
        (tmp / relative).write_bytes(content)
    return setup


def _kept(relative: str, content: bytes = b"mine"):
    def check(ran: Ran) -> None:
        assert (ran.out.parent / relative).read_bytes() == content
    return check


def _replaced(relative: str):
    def check(ran: Ran) -> None:
        assert set(np.load(ran.out.parent / relative)) >= {"imfs", "residue"}
    return check


def _noted(fragment: str):
    def check(ran: Ran) -> None:
        assert any(line.startswith("note: ") and fragment in line for line in ran.stdout.splitlines()), ran.stdout
    return check


def _truncate(relative: str):
    def setup(tmp: Path, inputs: Path) -> None:
        (tmp / relative).write_bytes(b"")
    return setup


def _scans(tmp: Path, inputs: Path) -> None:
    """``<tmp>/scans``: good.ply, ``scan[1].ply`` and a symlink loop ``loop -> .``."""
    (tmp / "scans").mkdir(exist_ok=True)
    shutil.copy(inputs / "good.ply", tmp / "scans" / "good.ply")
    shutil.copy(inputs / "good.ply", tmp / "scans" / "scan[1].ply")
    if not (tmp / "scans" / "loop").exists():
        (tmp / "scans" / "loop").symlink_to(".")


def _scans_run_once(tmp: Path, inputs: Path) -> None:
    """:func:`_scans`, then a run on that folder into itself, which leaves ``good_hht.ply`` there."""
    _scans(tmp, inputs)
    sets = [f"inputs={tmp}/scans", f"outputs.folder={tmp}/scans", PLY_OUTPUT]
    assert main(["run", str(tmp / "pipeline.yaml"), *[a for s in sets for a in ("--set", s)]]) == 0
    assert (tmp / "scans" / "good_hht.ply").is_file()


def _special_files(tmp: Path, inputs: Path) -> None:
    os.mkfifo(tmp / "fifo.ply")
    (tmp / "random.ply").symlink_to("/dev/urandom")


def _only_inputs(*names: str):
    def check(ran: Ran) -> None:
        reported = re.findall(r"^(\S.*?): ok", ran.stdout, flags=re.M)
        assert [Path(r).name for r in reported] == list(names), ran.stdout
    return check


def _summary_rows(*names: str):
    def check(ran: Ran) -> None:
        rows = json.loads((ran.out / "summary.json").read_text())
        assert sorted(Path(r["source"]).name for r in rows) == sorted(names)
    return check


def _written(name: str, folder: str = "out"):
    """A check: ``<tmp>/folder/name`` was written."""
    def check(ran: Ran) -> None:
        path = ran.out.parent / folder / name
        assert path.is_file() and path.stat().st_size > 0
    return check


def _embedded(ran: Ran) -> None:
    """The data URI's vertices are the bumpy sphere's (as float32), every one of them (in Open3D's order)."""
    def rows(a):
        return a[np.lexsort(np.round(a, 5).T)]

    np.testing.assert_allclose(rows(_npz(ran, "embedded")["vertices"]), rows(_bumpy()[0]), atol=1e-6)


def _strict_json(ran: Ran) -> None:
    """``info --json`` of a mesh near the coordinate limit: strict JSON (no NaN, no Infinity), finite area."""
    def refuse(constant):
        raise AssertionError(f"{constant} is not JSON")

    info = json.loads(ran.stdout, parse_constant=refuse)
    assert info["vertices"] == 162 and 1e139 < info["surface_area"] < 1e142


def _renamed_property(ran: Ran) -> None:
    header = PlyData.read(str(ran.out / "0bad_hht.ply"))["vertex"].data.dtype.names
    assert "_0bad" in header and "0bad" not in header


LONG = "n" * 240  # + "_hht.npz" (8): 248 bytes, legal; its temporary name would not be without cutting
SCANS = "outputs.folder=<tmp>/scans"
PLY_OUTPUT = "outputs.files=[{path: '{stem}_hht.ply'}]"
SAFETY_CASES = {
    "glTF buffer ../../etc/passwd": refused("passwd.gltf", "refers to '../../../../../../../../etc/passwd', "
                                                           "outside the file's folder"),
    "glTF buffer /etc/passwd": refused("absolute.gltf", "refers to '/etc/passwd', outside the file's folder"),
    "OBJ mtllib outside": refused("mtl_outside.obj", "outside the file's folder"),
    "glTF with an embedded buffer": accepted("embedded.gltf", check=_embedded),
    "output replaces the input": Case(run("outputs.folder=<in>", "outputs.files=[{path: '{stem}.ply'}]"),
                                      "is the input", absent=()),
    "output path ../../": Case(validate("outputs.files=[{path: '../../x_{stem}.npz'}]"),
                               "outside the output folder"),
    "absolute output path": Case(validate("outputs.files=[{path: '<tmp>/elsewhere/{stem}.npz'}]"),
                                 "outside the output folder", absent=("out", "elsewhere")),
    "{parent} that is ..": Case(validate("inputs=<in>/no_meshes/../good.ply",
                                         "outputs.files=[{path: '{parent}/{stem}.npz'}]"),
                                "output '{parent}/{stem}.npz' of step 'hht': "),
    "{name} that escapes": Case(validate("name=../../n", "outputs.files=[{path: '{name}_{stem}.npz'}]"),
                                "outside the output folder"),
    "allow_outside opts in": Case(run("outputs.allow_outside=true", "outputs.files=[{path: '../side/{stem}.npz'}]"),
                                  "", 0, (), check=_written("good.npz", "side")),
    "user's file under an output name": Case(run(), "exists and hht3d did not write it", absent=(),
                                            setup=_user_file("out/good_hht.npz"), check=_kept("out/good_hht.npz")),
    "validate notes a user's file under an output name": Case(validate(), "", 0, (),
                                                              setup=_user_file("out/good_hht.npz"),
                                                              check=_noted("good_hht.npz: exists and hht3d did not")),
    "--overwrite replaces it": Case((*run(), "--overwrite"), "", 0, (), setup=_user_file("out/good_hht.npz"),
                                    check=_replaced("out/good_hht.npz")),
    "--resume does not trust a 0-byte output": Case((*run(), "--resume"), "exists and hht3d did not write it",
                                                   absent=(), before=(run(),), setup=_truncate("out/good_hht.npz")),
    "--resume --overwrite redoes it": Case((*run(), "--resume", "--overwrite"), "", 0, (), before=(run(),),
                                           setup=_truncate("out/good_hht.npz"), check=_written("good_hht.npz")),
    "outputs are never inputs": Case(run("inputs=<tmp>/scans", SCANS, PLY_OUTPUT), "", 0, (), setup=_scans_run_once,
                                     check=_only_inputs("good.ply", "scan[1].ply")),
    "two pipelines share a summary": Case(run(SUMMARY, "inputs=<in>/huge.ply"), "", 0, (), before=(run(SUMMARY),),
                                          check=_summary_rows("good.ply", "huge.ply")),
    "format spec in a placeholder": Case(validate("outputs.files=[{path: '{stem:>9999999999}.npz'}]"),
                                         "has a format spec or conversion"),
    "conversion in a placeholder": Case(validate("outputs.files=[{path: '{stem!r}.npz'}]"),
                                        "has a format spec or conversion"),
    "248-byte output name": Case(run(f"outputs.files=[{{path: '{LONG}_hht.npz'}}]"), "", 0, (),
                                 check=_written(f"{LONG}_hht.npz")),
    "300-byte output name": Case(run(f"outputs.files=[{{path: '{'n' * 296}.npz'}}]"),
                                 "is 300 bytes long; the limit is 255"),
    "NUL in an output name": Case(run('outputs.files=[{path: "a\\0{stem}.npz"}]'), "holds a control character"),
    "existing file named like a glob": Case(run("inputs=<tmp>/scans/scan[1].ply", SCANS), "", 0, (), setup=_scans,
                                            check=_written("scan[1]_hht.npz", "scans")),
    "symlink loop listed once": Case(run("inputs=<tmp>/scans/**/good.ply", "outputs.files=[{path: '{stem}.npz'}]"),
                                     "", 0, (), setup=_scans, check=_only_inputs("good.ply")),
    "FIFO input": Case(("info", "<tmp>/fifo.ply"), "is a FIFO (named pipe), not a regular file", absent=(),
                       setup=_special_files),
    "symlink to /dev/urandom": Case(run("inputs=<tmp>/random.ply"), "is a character device, not a regular file",
                                    setup=_special_files),
    "view of a fake .npz": Case(("view", "<in>/fake.npz"), "not a readable .npz file"),
    "PLY property 0bad": Case(run("inputs=<in>/0bad.ply", "outputs.files=[{path: '{stem}_hht.ply'}]"), "", 0, (),
                              check=_renamed_property),
    "info --json of a mesh x1e300": Case(("info", "--json", "<in>/huge300.ply"), "huge300.ply: huge300: coordinates "
                                         "reach 1.06e+300; beyond 1e+75 areas and curvatures overflow float64"),
    "run on a mesh x1e300": Case(run("inputs=<in>/huge300.ply"), "coordinates reach 1.06e+300; beyond 1e+75"),
    "info --json of a mesh x1e70": Case(("info", "--json", "<in>/huge70.ply"), "", 0, (), check=_strict_json),
    "spectrum figure of max_imfs 0": Case(validate("steps.hht.params.max_imfs=0",
                                                   "outputs.files=[{path: x.png, figure: spectrum}]"),
                                          "a spectrum figure needs IMFs"),
    "a plain list of 200,000 inputs": Case(validate(), "the YAML holds more than 100000 values",
                                           yaml=PIPELINE.replace('inputs: "<in>/good.ply"', "inputs: [" + ", ".join(
                                               ["a.ply"] * 200_000) + "]")),
    "malformed --address": Case((*run(), "--address", "http://[::1"), "cannot reach the Dask scheduler"),
}

CASES = {
    # 1. output locations that cannot be written: refused by validate and before run computes anything
    "read-only output folder": Case(run("outputs.folder=<tmp>/read-only/out"), "Permission denied",
                                    absent=("read-only/out",), unprivileged=True, issue=True),
    "output folder under /proc, validate": Case(validate("outputs.folder=/proc/hht3d-out"),
                                                "creating anything in /proc fails", issue=True),
    "output folder under /proc, run": Case(run("outputs.folder=/proc/hht3d-out"),
                                           "creating anything in /proc fails", issue=True),
    "output folder is a file, validate": Case(validate("outputs.folder=<in>/good.ply"),
                                              "good.ply is not a folder; choose another output folder", issue=True),
    "output folder under a file, run": Case(run("outputs.folder=<in>/good.ply/out"), "good.ply is not a folder",
                                            issue=True),
    "demo --out /dev/full": Case(("demo", "--out", "/dev/full", "--quiet"), "/dev/full is not a folder", issue=True),
    "output file is a folder": Case(run("outputs.folder=<tmp>", "outputs.files=[{path: taken.npz}]"),
                                    "taken.npz: cannot write: a folder of that name is in the way",
                                    absent=("taken.npz/good_hht.npz",)),
    "full disk while writing summary.json": Case(
        run(TWO_GOOD, SUMMARY), "summary.json: cannot write (No space left", absent=("out/summary.json",),
        fault=_failing_write("summary.json", errno.ENOSPC), check=_every_line_printed, issue=True),
    "summary.csv not permitted": Case(
        run(TWO_GOOD, SUMMARY), "summary.csv: cannot write (Permission denied)", absent=("out/summary.csv",),
        fault=_failing_write("summary.csv", errno.EACCES), check=_every_line_printed, issue=True),
    # 2. flat point clouds: a result, and no Qhull output
    "exactly flat point cloud (z = 0)": accepted("flat_cloud.ply", check=_flat_cloud, issue=True),
    "tilted flat point cloud": accepted("tilted_cloud.ply", check=_nearly_flat("tilted_cloud"), issue=True),
    "nearly flat point cloud (1e-12)": accepted("nearly_flat_cloud.ply", check=_nearly_flat("nearly_flat_cloud"),
                                                issue=True),
    "points on a line": refused("line_cloud.ply", "50 points lie on a line"),
    # 3. upper bounds, checked without building the graph
    "riesz_tasks: 100000": Case(validate("steps.hht.params.riesz_tasks=100000"),
                                "riesz_tasks must be an integer in [1, 64]; got 100000", issue=True),
    "riesz_tasks: 5000 in run": Case(run("steps.hht.params.riesz_tasks=5000"), "riesz_tasks must be an integer in",
                                     issue=True),
    "ensemble_size: 1e9": Case(validate(), "ensemble_size must be an integer in [1, 1000]; got 1000000000.0",
                               yaml=PIPELINE.replace("max_imfs: 2", "ensemble_size: 1e9"), issue=True),
    "ensemble_size: 1000000000": Case(validate("steps.hht.params.ensemble_size=1000000000"),
                                      "ensemble_size must be an integer in [1, 1000]", issue=True),
    "the largest ensemble validates without a graph": Case(
        validate("steps.hht.params.ensemble_size=1000", "steps.hht.params.riesz_tasks=64"), "", 0, (),
        fault=_no_graph, issue=True),
    "max_imfs: 1000": Case(validate("steps.hht.params.max_imfs=1000"), "max_imfs must be an integer in [0, 64]",
                           issue=True),
    "eigenpairs: 100000": Case(validate("steps.hht.params.eigenpairs=100000"),
                               "eigenpairs must be an integer in [1, 2000]", issue=True),
    "--workers 100000": Case((*run(), "--workers", "100000"), "workers must be an integer in [1, 256]", issue=True),
    "execution.workers: 100000": Case(validate("execution.workers=100000"), "workers must be an integer in [1, 256]",
                                      issue=True),
    "sd_threshold: 1e6": Case(validate("steps.hht.params.sd_threshold=1e6"),
                              "sd_threshold must be a number in [0, 10]"),
    "seed: 2**64": Case(validate("execution.seed=18446744073709551616"), "seed must be an integer in [0, 4294967295]"),
    "max_sifts: 10**9": Case(validate("steps.hht.params.max_sifts=1000000000"), "max_sifts must be an integer in"),
    "n_neighbors: 10**6": Case(validate("steps.load.params.n_neighbors=1000000"), "n_neighbors must be an integer in"),
    # 4. echoed values are cut; YAML aliases cannot explode
    "YAML alias bomb (9^9 values)": Case(validate(), "expands to more than 100000 values through aliases",
                                         yaml=f"{PIPELINE}bomb: {_alias_bomb(9)}\n", issue=True),
    "alias bomb below the limit as a parameter": Case(
        validate(), "parameter kind must be one of", issue=True,
        yaml=PIPELINE.replace("kind: mean_curvature", f"kind: {_alias_bomb(5)}")),
    "recursive alias": Case(validate(), "an alias refers to its own anchor", yaml=PIPELINE + "loop: &l [*l]\n"),
    "megabyte value": Case(validate("steps.curvature.params.kind=" + "x" * 1_000_000), "parameter kind must be one of",
                           issue=True),
    "deeply nested YAML": Case(validate(), "the YAML is nested too deeply", yaml=PIPELINE + "deep: " + "[" * 3000),
    # 5. facts cheap to know are checked by validate
    "input with an unknown extension": Case(validate("inputs=<in>/notes.txt"), "unknown extension '.txt'", issue=True),
    "eigenpairs above the vertex count": Case(validate("steps.hht.params.method=spectral"),
                                              "eigenpairs: 300 needs at least 301 vertices, but", issue=True),
    "eigenpairs above the vertex count of a baseline": Case(
        validate("steps.hht.op=manifold_harmonics_filter",
                 "steps.hht.params={gain: {kind: constant}, eigenpairs: 162}", "outputs.files=[{path: x.ply}]"),
        "eigenpairs: 162 needs at least 163 vertices"),
    "field imf_9 with max_imfs: 2": Case(validate("outputs.files=[{path: x.ply, field: imf_9}]"),
                                         "field imf_9 needs 9 IMFs, but step 'hht' makes at most max_imfs: 2",
                                         issue=True),
    "kind: file signal that is not .npy": Case(
        validate("steps.curvature.params={kind: file, path: <in>/signal.csv}"),
        "signal.csv: a signal file must be a .npy file written by numpy.save", issue=True),
    "kind: file signal that is missing": Case(validate("steps.curvature.params={kind: file, path: <in>/none.npy}"),
                                              "none.npy: no such signal file"),
    "kind: file signal of Python objects": Case(run("steps.curvature.params={kind: file, path: <in>/objects.npy}"),
                                                "not a .npy file of numbers (it holds Python objects"),
    "kind: file signal of the wrong length": Case(run("steps.curvature.params={kind: file, path: <in>/short.npy}"),
                                                  "has shape (5,); good has 162 vertices"),
    # 6. the smaller messages
    "info on a folder": Case(("info", "<in>"), "is a folder, not a mesh or point-cloud file", issue=True),
    "complex signal": Case(run("steps.curvature.params={kind: file, path: <in>/complex.npy}"),
                           "complex.npy is complex; pass a real signal", issue=True),
    "gain without cutoff": Case(validate("steps.hht.op=filter_signal", "steps.hht.params={gain: {kind: low_pass}}",
                                         "steps.hht.from=null", "outputs.files=[{path: x.npz}]"),
                                "gain low_pass needs cutoff: {kind: low_pass, cutoff: ...}", issue=True),
    "unknown EMD option (YAML side)": Case(validate("steps.hht.params.max_imf=2"),
                                           "unknown parameter 'max_imf'; did you mean 'max_imfs'?", issue=True),
    "--resume fills the skipped row": Case((*run(SUMMARY), "--resume"), "", 0, (), before=(run(SUMMARY),),
                                           check=_resumed, issue=True),
    "failed later step lists the earlier output": Case(
        run(SUMMARY, "steps.hht.params.max_imfs=5", "outputs.files=[{from: curvature, path: '{stem}_signal.npz'}, "
                                                    "{path: '{stem}_imf_5.ply', field: imf_5}]"),
        "step write good_imf_5.ply failed", absent=("out/good_imf_5.ply",), check=_partial, issue=True),
    "progress into a log": Case(run("execution.progress=true"), "", 0, (), issue=True),
    "quality in the row and the summary": Case(run(SUMMARY), "", 0, (), check=_quality_columns, issue=True),
    "a warning exits 0 and is printed": Case(run(SUMMARY, "steps.curvature.params={kind: file, path: <in>/spike.npy}"),
                                             "", 0, (), check=_warned, issue=True),
    # beyond the issue: meshes and point clouds as found in the wild
    "non-manifold edge": accepted("non_manifold.ply", check=_non_manifold),
    "zero-area component": accepted("good.ply", "zero_area.ply", check=_zero_area),
    "huge coordinates (1e30)": accepted("good.ply", "huge.ply", check=_same_as_good("huge", 1e30)),
    "tiny coordinates (1e-30)": accepted("good.ply", "tiny.ply", check=_same_as_good("tiny", 1e-30)),
    "mixed triangle/quad PLY": accepted("mixed.ply", check=_mixed),
    "big-endian binary PLY": accepted("good.ply", "big_endian.ply", check=_same_as_good("big_endian")),
    "ASCII PLY": accepted("good.ply", "ascii.ply", check=_same_as_good("ascii")),
    "vertex_indices as uint32": accepted("good.ply", "uint32.ply", check=_same_as_good("uint32")),
    "vertex_indices as int8": accepted("int8.ply", check=_int8),
    "Unicode and spaces in paths": Case(run('inputs="<in>/dossier é ü/modèle 3d/tête à claque.ply"',
                                            'outputs.folder="<out>/résultats 1"'), "", 0, (),
                                        check=lambda ran: _unicode(Ran(ran.inputs, ran.out / "résultats 1",
                                                                       ran.stdout))),
    "disconnected components": accepted("two_parts.ply", check=_two_parts),
    "constant signal": Case(run("inputs=<in>/plane_at_2.ply", "steps.curvature.params.kind=z"), "", 0, (),
                            check=_constant),
    "NaN coordinates": refused("nan.ply", "1 vertices have NaN or infinite coordinates (first: vertex 5)"),
    "infinite coordinates": refused("infinite.ply", "NaN or infinite coordinates (first: vertex 7)"),
    "too few vertices": refused("three.ply", "3 vertices; a surface needs at least 4"),
    "every point the same": refused("same_point.ply", "1 vertices; a surface needs at least 4"),
    "every face degenerate": refused("all_degenerate.ply", "0 vertices; a surface needs at least 4"),
    "face index out of range": refused("bad_index.ply", "face indices must lie in [0, 162), got [0, 500]"),
    "point cloud smaller than n_neighbors": refused("ten.xyz",
                                                    "a point cloud of 10 points cannot give each point n_neighbors=30"),
    "empty PLY": refused("empty.ply", "empty.ply: not a readable PLY file"),
    "empty XYZ": refused("empty.xyz", "empty.xyz: the file holds no vertices"),
    "truncated binary PLY": refused("truncated.ply", "not a readable PLY file (element 'face'"),
    "unreadable OBJ": refused("garbage.obj", "garbage.obj: the file holds no vertices"),
    "missing input": Case(validate("inputs=<in>/nowhere.ply"), "nowhere.ply: no such file or folder"),
    "folder without meshes": Case(validate("inputs=<in>/no_meshes"), "matches no mesh or point-cloud file"),
    "stored attribute that is not there": Case(run("steps.curvature.params={kind: stored, attribute: height}"),
                                               "no stored vertex attribute 'height'"),
    "luminance without colours": Case(run("steps.curvature.params.kind=luminance"), "has no vertex colours"),
    "pipeline that is not UTF-8": Case(("validate", "<in>/latin1.yaml"), "byte 20 is not UTF-8 text"),
    "pipeline that is a folder": Case(("validate", "<in>"), "cannot read the pipeline (Is a directory)"),
    "empty pipeline": Case(validate(), "got an empty file", yaml=""),
    "YAML syntax error": Case(validate(), "pipeline.yaml:6:3: YAML syntax error: while parsing a flow mapping",
                              yaml=PIPELINE.replace("mean_curvature}}", "mean_curvature}")),
    "--set without =": Case(validate("steps.hht.params.max_imfs"), "expected KEY.PATH=VALUE"),
    "step id of 100 characters": Case(validate("steps.hht.id=" + "h" * 100), "step id must be 1 to 64 letters"),
    **SAFETY_CASES,
}


def _substitute(text: str, places: dict) -> str:
    for key, value in places.items():
        text = text.replace(f"<{key}>", str(value))
    return text


def _unprivileged(argv: list[str]) -> subprocess.CompletedProcess:
    """Run the CLI without root's override of file permissions (as root: drop CAP_DAC_OVERRIDE)."""
    prefix = []
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("root ignores read-only folders and setpriv is not installed to drop that")
        prefix = [setpriv, "--bounding-set=-dac_override,-dac_read_search"]
    done = subprocess.run([*prefix, sys.executable, "-m", "hht3d", *argv], capture_output=True, text=True,
                          cwd=ROOT, timeout=300, check=False)
    if "setpriv" in done.stderr:
        pytest.skip(f"cannot drop root's permission override here: {done.stderr.strip()}")
    return done


def _leftovers(*folders: Path) -> list[Path]:
    return [p for folder in folders for pattern in ("**/*.part", "**/.hht3d-probe-*") for p in folder.glob(pattern)]


@pytest.mark.parametrize("name", CASES)
def test_bad_input(name, inputs, tmp_path, capfd, monkeypatch):
    case = CASES[name]
    places = {"in": inputs, "out": tmp_path / "out", "tmp": tmp_path, "pipeline": tmp_path / "pipeline.yaml"}
    (tmp_path / "pipeline.yaml").write_text(_substitute(case.yaml, places), encoding="utf-8")
    (tmp_path / "taken.npz").mkdir()
    (tmp_path / "read-only").mkdir(mode=0o555)
    for before in case.before:
        assert main([_substitute(a, places) for a in before]) == 0
    if case.setup is not None:
        case.setup(tmp_path, inputs)
    capfd.readouterr()
    argv = [_substitute(a, places) for a in case.argv]
    if case.fault is not None:
        case.fault(monkeypatch)
    if case.unprivileged:
        done = _unprivileged(argv)
        code, out, err = done.returncode, done.stdout, done.stderr
    else:
        code = main(argv)
        out, err = capfd.readouterr()
    assert code == case.code, err
    if case.code == 0:
        assert err == "", err  # no Qhull or Open3D output, no progress bar redrawn into a log
    else:
        assert err.startswith("hht3d: error: ") and err.count("\n") == 1 and len(err) < 2100, err[:3000]
        assert case.message in err, err
    for path in case.absent:
        assert not (tmp_path / path).exists(), path
    assert not _leftovers(tmp_path, inputs)
    if case.check is not None:
        case.check(Ran(inputs, tmp_path / "out", out))


#: Numeric parameters in model units, which scale with the model: only required to be finite.
MODEL_UNITS = {"merge_radius", "time"}


def test_every_numeric_parameter_has_an_upper_bound():
    """Issue 15: a typo such as riesz_tasks: 100000 must be refused, so every new parameter needs a maximum."""
    params = [p for op in OPERATIONS.values() for p in op.params] + list(EXECUTION)
    unbounded = {p.name for p in params if p.kind in ("int", "float") and p.maximum is None} - MODEL_UNITS
    assert not unbounded, f"give these parameters a maximum (hht3d/pipeline/registry.py): {sorted(unbounded)}"


def test_progress_into_a_log_is_a_few_plain_lines(monkeypatch, capfd):
    """A long run into a log (stderr not a terminal): a line per interval, not a bar redrawn 10 times a second."""
    monkeypatch.setattr("hht3d.graph.scheduling.PROGRESS_INTERVAL", 0.1)
    tasks = [delayed(time.sleep, pure=False)(0.02) for _ in range(40)]
    compute(*tasks, scheduler="synchronous", progress=True)
    lines = capfd.readouterr().err.splitlines()
    assert 3 <= len(lines) <= 12, lines
    assert all(re.fullmatch(r"hht3d: \d+% of 40 tasks done, \d+ s", line) for line in lines), lines
    assert lines[-1].startswith("hht3d: 100% of 40 tasks done")


# -- every value of a pipeline replaced by an odd one ---------------------------------------------------
FULL = {
    "version": 1, "name": "odd",
    "execution": {"scheduler": "threads", "workers": 2, "progress": False, "seed": 3},
    "inputs": ["<in>/good.ply"],
    "steps": [
        {"id": "load", "op": "load", "params": {"clean": True, "laplacian": "cotan", "n_neighbors": 20}},
        {"id": "curvature", "op": "signal", "params": {"kind": "mean_curvature"}},
        {"id": "hht", "op": "hht", "from": {"signal": "curvature"},
         "params": {"max_imfs": 2, "tol": 0.001, "ensemble_size": 3, "riesz_tasks": 2}},
        {"id": "smooth", "op": "filter_geometry", "params": {"gain": {"kind": "band_stop", "low": 1, "high": 2}}},
        {"id": "features", "op": "features", "from": "hht", "params": {"ratio": 0.8}},
    ],
    "outputs": {"folder": "<out>", "summary": True, "files": [
        {"from": "hht", "path": "{stem}_hht.ply", "field": "imf_1", "cmap": "viridis"},
        {"from": "hht", "path": "{stem}.png", "figure": "hht", "view": "front"},
        {"from": "features", "path": "{stem}_features.npz"},
    ]},
}
ODD = {"list": [1], "mapping": {"a": 1}, "null": None, "negative": -1, "huge number": 10 ** 30,
       "long string": "x" * 10_000}


def _places(node, path=()):
    """The path of every value in a nested document."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        yield (*path, key)
        yield from _places(value, (*path, key))


@pytest.mark.parametrize("odd", ODD)
def test_any_value_replaced_by_an_odd_one_is_a_clear_error(odd, inputs, tmp_path):
    document = json.loads(_substitute(json.dumps(FULL), {"in": inputs, "out": tmp_path / "out"}))
    parse_pipeline(yaml.safe_dump(document))  # the document itself is valid
    for place in _places(document):
        changed = copy.deepcopy(document)
        node = changed
        for key in place[:-1]:
            node = node[key]
        node[place[-1]] = ODD[odd]
        try:
            parse_pipeline(yaml.safe_dump(changed))
        except HHT3DError as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 1000, (place, str(exc)[:300])
    assert not (tmp_path / "out").exists()


# -- issue 23: the folders around a run ---------------------------------------------------------------------------
def _checksums(root: Path, skip: Path) -> dict:
    """SHA-256 of every file below ``root`` (symlinks as their targets' text), except below ``skip``."""
    import hashlib

    listing = {}
    for path in sorted(root.rglob("*")):
        if path == skip or skip in path.parents:
            continue
        if path.is_symlink():
            listing[str(path)] = f"-> {os.readlink(path)}"
        elif path.is_file():
            listing[str(path)] = hashlib.sha256(path.read_bytes()).hexdigest()
        else:
            listing[str(path)] = "folder"
    return listing


@pytest.mark.parametrize("sets", [
    (), ("outputs.files=[{path: '../../x_{stem}.npz'}]",), ("outputs.files=[{path: '{name}.npz'}]", "name=../n"),
    ("outputs.folder=<in>", "outputs.files=[{path: '{stem}.ply'}]"),
], ids=["a run", "escaping path", "escaping name", "over its input"])
def test_nothing_around_a_run_changes_but_its_output_folder(sets, inputs, tmp_path):
    """A checksum listing of the folders around a run (its inputs, their parent, the working folder's
    neighbours) is the same after it, whether it ran or was refused; only the output folder changed."""
    around = tmp_path.parent
    pipeline = tmp_path / "pipeline.yaml"
    places = {"in": inputs, "out": tmp_path / "out"}
    pipeline.write_text(_substitute(PIPELINE, places), encoding="utf-8")
    before = _checksums(around, tmp_path / "out")
    code = main(["run", str(pipeline), *[a for s in sets for a in ("--set", _substitute(s, places))]])
    assert code == (0 if not sets else 1)
    assert _checksums(around, tmp_path / "out") == before


@pytest.mark.parametrize("options, message", [
    ({"formats": (".obj",)}, "unknown output format '.obj'"),
    ({"signal": "bogus"}, "unknown signal 'bogus'"),
])
def test_run_dataset_refuses_bad_options_before_building_the_graph(options, message, inputs, tmp_path, monkeypatch):
    from hht3d.errors import InputError
    from hht3d.graph.dataset import run_dataset

    monkeypatch.setattr("hht3d.graph.stages.transform_file", lambda *a, **k: pytest.fail("built the graph"))
    with pytest.raises(InputError, match=re.escape(message)):
        run_dataset([inputs / "good.ply"], tmp_path / "out", scheduler="synchronous", progress=False, **options)
    assert not (tmp_path / "out").exists()


def test_riesz_tasks_zero_is_named(inputs):
    from hht3d import graph
    from hht3d.errors import InputError

    surface = load(inputs / "good.ply")
    with pytest.raises(InputError, match="riesz_tasks must be an integer >= 1, got 0"):
        graph.hht(surface, surface.vertices[:, 0], riesz_tasks=0)

