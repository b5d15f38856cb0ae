"""Bad inputs about files and paths (issues 15 and 23): unknown, empty, truncated and special files, references
outside a file's folder, signal files, Unicode paths, names like globs, symlink loops.

One table row each, run by :func:`helpers.bad_inputs.run_case` (what a row holds and checks is told there).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from helpers.bad_files import _bumpy
from helpers.bad_inputs import (
    SCANS,
    Case,
    Ran,
    _npz,
    _only_inputs,
    _scans,
    _written,
    accepted,
    refused,
    run,
    run_case,
    validate,
)


# -- checks of correct results ----------------------------------------------------------------------------------
def _unicode(ran: Ran) -> None:
    (path,) = ran.out.glob("*.npz")
    assert path.name == "tête à claque_hht.npz"
    assert "tête à claque.ply: ok, 162 vertices" in ran.stdout


def _special_files(tmp: Path, inputs: Path) -> None:
    os.mkfifo(tmp / "fifo.ply")
    (tmp / "random.ply").symlink_to("/dev/urandom")


def _embedded(ran: Ran) -> None:
    """The data URI's vertices are the bumpy sphere's (as float32), every one of them (in Open3D's order)."""

    def rows(a):
        return a[np.lexsort(np.round(a, 5).T)]

    np.testing.assert_allclose(rows(_npz(ran, "embedded")["vertices"]), rows(_bumpy()[0]), atol=1e-6)


CASES = {
    # 5. facts cheap to know are checked by validate
    "input with an unknown extension": Case(validate("inputs=<in>/notes.txt"), "unknown extension '.txt'", issue=True),
    "kind: file signal that is not .npy": Case(
        validate("steps.curvature.params={kind: file, path: <in>/signal.csv}"),
        "signal.csv: a signal file must be a .npy file written by numpy.save",
        issue=True,
    ),
    "kind: file signal that is missing": Case(
        validate("steps.curvature.params={kind: file, path: <in>/none.npy}"), "none.npy: no such signal file"
    ),
    "kind: file signal of Python objects": Case(
        run("steps.curvature.params={kind: file, path: <in>/objects.npy}"),
        "not a .npy file of numbers (it holds Python objects",
    ),
    "kind: file signal of the wrong length": Case(
        run("steps.curvature.params={kind: file, path: <in>/short.npy}"), "has shape (5,); good has 162 vertices"
    ),
    # 6. the smaller messages
    "info on a folder": Case(("info", "<in>"), "is a folder, not a mesh or point-cloud file", issue=True),
    "complex signal": Case(
        run("steps.curvature.params={kind: file, path: <in>/complex.npy}"),
        "complex.npy is complex; pass a real signal",
        issue=True,
    ),
    "Unicode and spaces in paths": Case(
        run('inputs="<in>/dossier é ü/modèle 3d/tête à claque.ply"', 'outputs.folder="<out>/résultats 1"'),
        "",
        0,
        (),
        check=lambda ran: _unicode(Ran(ran.inputs, ran.out / "résultats 1", ran.stdout)),
    ),
    "empty PLY": refused("empty.ply", "empty.ply: not a readable PLY file"),
    "empty XYZ": refused("empty.xyz", "empty.xyz: the file holds no vertices"),
    "truncated binary PLY": refused("truncated.ply", "not a readable PLY file (element 'face'"),
    "unreadable OBJ": refused("garbage.obj", "garbage.obj: the file holds no vertices"),
    "missing input": Case(validate("inputs=<in>/nowhere.ply"), "nowhere.ply: no such file or folder"),
    "folder without meshes": Case(validate("inputs=<in>/no_meshes"), "matches no mesh or point-cloud file"),
    # issue 23: nothing read outside where it belongs
    "glTF buffer ../../etc/passwd": refused(
        "passwd.gltf", "refers to '../../../../../../../../etc/passwd', outside the file's folder"
    ),
    "glTF buffer /etc/passwd": refused("absolute.gltf", "refers to '/etc/passwd', outside the file's folder"),
    "OBJ mtllib outside": refused("mtl_outside.obj", "outside the file's folder"),
    "glTF with an embedded buffer": accepted("embedded.gltf", check=_embedded),
    "existing file named like a glob": Case(
        run("inputs=<tmp>/scans/scan[1].ply", SCANS),
        "",
        0,
        (),
        setup=_scans,
        check=_written("scan[1]_hht.npz", "scans"),
    ),
    "symlink loop listed once": Case(
        run("inputs=<tmp>/scans/**/good.ply", "outputs.files=[{path: '{stem}.npz'}]"),
        "",
        0,
        (),
        setup=_scans,
        check=_only_inputs("good.ply"),
    ),
    "FIFO input": Case(
        ("info", "<tmp>/fifo.ply"), "is a FIFO (named pipe), not a regular file", absent=(), setup=_special_files
    ),
    "symlink to /dev/urandom": Case(
        run("inputs=<tmp>/random.ply"), "is a character device, not a regular file", setup=_special_files
    ),
    "view of a fake .npz": Case(("view", "<in>/fake.npz"), "not a readable .npz file"),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_input(name, inputs, tmp_path, capfd, monkeypatch):
    run_case(CASES[name], inputs, tmp_path, capfd, monkeypatch)
