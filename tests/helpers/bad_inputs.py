"""The table of bad inputs to the ``hht3d`` command (issue 15; tests/cli/test_bad_*.py): its rows and how one runs.

Every row is an input (CLI arguments, the pipeline text, the files in the
input folder), the expected fragment of the message, the exit code and the
files that must not exist afterwards.  An error is one ``hht3d: error: ...``
line on stderr with exit code 1; a success prints nothing on stderr (no
Qhull or Open3D chatter, no progress bar in a log) and, where the input is
odd but valid, its row checks the numbers of the result.  After every row no
temporary (``.part``) or probe file is left anywhere.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from hht3d.cli import main

ROOT = Path(__file__).resolve().parents[2]

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


# -- the user's folders (issue 23) --------------------------------------------------------------------------
def _scans(tmp: Path, inputs: Path) -> None:
    """``<tmp>/scans``: good.ply, ``scan[1].ply`` and a symlink loop ``loop -> .``."""
    (tmp / "scans").mkdir(exist_ok=True)
    shutil.copy(inputs / "good.ply", tmp / "scans" / "good.ply")
    shutil.copy(inputs / "good.ply", tmp / "scans" / "scan[1].ply")
    if not (tmp / "scans" / "loop").exists():
        (tmp / "scans" / "loop").symlink_to(".")


def _only_inputs(*names: str):
    def check(ran: Ran) -> None:
        reported = re.findall(r"^(\S.*?): ok", ran.stdout, flags=re.M)
        assert [Path(r).name for r in reported] == list(names), ran.stdout

    return check


def _written(name: str, folder: str = "out"):
    """A check: ``<tmp>/folder/name`` was written."""

    def check(ran: Ran) -> None:
        path = ran.out.parent / folder / name
        assert path.is_file() and path.stat().st_size > 0

    return check


SCANS = "outputs.folder=<tmp>/scans"


# -- one row ----------------------------------------------------------------------------------------------------
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
    done = subprocess.run(
        [*prefix, sys.executable, "-m", "hht3d", *argv],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
        check=False,
    )
    if "setpriv" in done.stderr:
        pytest.skip(f"cannot drop root's permission override here: {done.stderr.strip()}")
    return done


def _leftovers(*folders: Path) -> list[Path]:
    return [p for folder in folders for pattern in ("**/*.part", "**/.hht3d-probe-*") for p in folder.glob(pattern)]


def run_case(case: Case, inputs: Path, tmp_path: Path, capfd, monkeypatch) -> None:
    """Run one row as ``test_bad_input`` does: the runs made first, the user's files, the fault, the
    command; then its exit code and stderr, the paths that must be absent, no leftovers, the row's check."""
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
