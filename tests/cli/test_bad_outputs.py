"""Bad inputs about where a run writes (issues 15 and 23): output folders that cannot be written, files in
the way, names that leave the output folder, the summary, resumed and partly failed runs.

One table row each, run by :func:`helpers.bad_inputs.run_case` (what a row holds and checks is told there).
"""

from __future__ import annotations

import errno
import json
import os
import pathlib
from pathlib import Path

import numpy as np
import pytest

from helpers.bad_inputs import (
    PIPELINE,
    SCANS,
    Case,
    Ran,
    _only_inputs,
    _scans,
    _substitute,
    _written,
    run,
    run_case,
    validate,
)
from hht3d.cli import main


# -- checks of correct results ----------------------------------------------------------------------------------
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


def _scans_run_once(tmp: Path, inputs: Path) -> None:
    """:func:`_scans`, then a run on that folder into itself, which leaves ``good_hht.ply`` there."""
    _scans(tmp, inputs)
    sets = [f"inputs={tmp}/scans", f"outputs.folder={tmp}/scans", PLY_OUTPUT]
    assert main(["run", str(tmp / "pipeline.yaml"), *[a for s in sets for a in ("--set", s)]]) == 0
    assert (tmp / "scans" / "good_hht.ply").is_file()


def _summary_rows(*names: str):
    def check(ran: Ran) -> None:
        rows = json.loads((ran.out / "summary.json").read_text())
        assert sorted(Path(r["source"]).name for r in rows) == sorted(names)

    return check


def _manifest(files, *, user: str | None = None):
    """A setup: ``out/.hht3d-manifest.json`` holding ``files`` (JSON text, or its value), and the user's own file
    at ``<tmp>/user`` if given; ``"<mine>"`` in ``files`` is the size and SHA-256 of that file."""
    import hashlib

    def setup(tmp: Path, inputs: Path) -> None:
        if user is not None:
            _user_file(user)(tmp, inputs)
        text = files if isinstance(files, str) else json.dumps(files)
        mine = {"size": 4, "sha256": hashlib.sha256(b"mine").hexdigest(), "run": "planted"}
        (tmp / "out").mkdir(exist_ok=True)
        (tmp / "out" / ".hht3d-manifest.json").write_text(text.replace('"<mine>"', json.dumps(mine)))

    return setup


def _recorded(*names: str):
    """A check: the manifest of ``out`` is valid and records ``names``."""

    def check(ran: Ran) -> None:
        from hht3d.io.manifest import entries

        files = json.loads((ran.out / ".hht3d-manifest.json").read_text())["files"]
        assert set(entries(ran.out)) >= set(names) and all(isinstance(entry, dict) for entry in files.values())

    return check


def _lock_file(make):
    """A setup: ``out/.hht3d.lock`` made by ``make(lock, tmp)``."""

    def setup(tmp: Path, inputs: Path) -> None:
        (tmp / "out").mkdir(exist_ok=True)
        make(tmp / "out" / ".hht3d.lock", tmp)

    return setup


def _dead_part(tmp: Path, inputs: Path) -> None:
    from helpers.folders import dead_writers_part

    dead_writers_part(tmp / "out", "good_hht.npz")


def _swapped_after_checks(monkeypatch) -> None:
    """A fault: once the run has checked its outputs, their folder ``out/sub`` is swapped for a link to
    ``<tmp>/elsewhere`` (where the user keeps a file of the output's name)."""
    from hht3d.io.folder import OutputFolder

    prepare = OutputFolder.prepare

    def swap(self, paths, **options):
        prepare(self, paths, **options)
        sub = Path(paths[0]).parent
        sub.rmdir()
        sub.symlink_to(sub.parent.parent / "elsewhere")

    monkeypatch.setattr(OutputFolder, "prepare", swap)


def _folder_and_user_file(tmp: Path, inputs: Path) -> None:
    (tmp / "out" / "sub").mkdir(parents=True)
    _user_file("elsewhere/good_hht.npz")(tmp, inputs)


FILE_URL = "outputs.folder=file://<tmp>/out"
MALFORMED = {
    "a list": "[]",
    "not JSON": "{files",
    "an entry a list": '{"files": {"good_hht.npz": [1]}}',
    "an entry a string": '{"files": {"good_hht.npz": "x"}}',
    "a size that is a string": '{"files": {"good_hht.npz": {"size": "4", "sha256": "00"}}}',
    "a size that is null": '{"files": {"good_hht.npz": {"size": null, "sha256": null}}}',
}
LONG = "n" * 240  # + "_hht.npz" (8): 248 bytes, legal; its temporary name would not be without cutting
PLY_OUTPUT = "outputs.files=[{path: '{stem}_hht.ply'}]"

CASES = {
    # 1. output locations that cannot be written: refused by validate and before run computes anything
    "read-only output folder": Case(
        run("outputs.folder=<tmp>/read-only/out"),
        "Permission denied",
        absent=("read-only/out",),
        unprivileged=True,
        issue=True,
    ),
    "output folder under /proc, validate": Case(
        validate("outputs.folder=/proc/hht3d-out"), "creating anything in /proc fails", issue=True
    ),
    "output folder under /proc, run": Case(
        run("outputs.folder=/proc/hht3d-out"), "creating anything in /proc fails", issue=True
    ),
    "output folder is a file, validate": Case(
        validate("outputs.folder=<in>/good.ply"), "good.ply is not a folder; choose another output folder", issue=True
    ),
    "output folder under a file, run": Case(
        run("outputs.folder=<in>/good.ply/out"), "good.ply is not a folder", issue=True
    ),
    "demo --out /dev/full": Case(("demo", "--out", "/dev/full", "--quiet"), "/dev/full is not a folder", issue=True),
    "output file is a folder": Case(
        run("outputs.folder=<tmp>", "outputs.files=[{path: taken.npz}]"),
        "taken.npz: cannot write: a folder of that name is in the way",
        absent=("taken.npz/good_hht.npz",),
    ),
    "full disk while writing summary.json": Case(
        run(TWO_GOOD, SUMMARY),
        "summary.json: cannot write (No space left",
        absent=("out/summary.json",),
        fault=_failing_write("summary.json", errno.ENOSPC),
        check=_every_line_printed,
        issue=True,
    ),
    "summary.csv not permitted": Case(
        run(TWO_GOOD, SUMMARY),
        "summary.csv: cannot write (Permission denied)",
        absent=("out/summary.csv",),
        fault=_failing_write("summary.csv", errno.EACCES),
        check=_every_line_printed,
        issue=True,
    ),
    # runs and their summaries
    "--resume fills the skipped row": Case(
        (*run(SUMMARY), "--resume"), "", 0, (), before=(run(SUMMARY),), check=_resumed, issue=True
    ),
    "failed later step lists the earlier output": Case(
        run(
            SUMMARY,
            "steps.hht.params.max_imfs=5",
            "outputs.files=[{from: curvature, path: '{stem}_signal.npz'}, {path: '{stem}_imf_5.ply', field: imf_5}]",
        ),
        "step write good_imf_5.ply failed",
        absent=("out/good_imf_5.ply",),
        check=_partial,
        issue=True,
    ),
    "progress into a log": Case(run("execution.progress=true"), "", 0, (), issue=True),
    "quality in the row and the summary": Case(run(SUMMARY), "", 0, (), check=_quality_columns, issue=True),
    "a warning exits 0 and is printed": Case(
        run(SUMMARY, "steps.curvature.params={kind: file, path: <in>/spike.npy}"), "", 0, (), check=_warned, issue=True
    ),
    # issue 23: nothing written outside where it belongs
    "output replaces the input": Case(
        run("outputs.folder=<in>", "outputs.files=[{path: '{stem}.ply'}]"), "is the input", absent=()
    ),
    "output path ../../": Case(validate("outputs.files=[{path: '../../x_{stem}.npz'}]"), "outside the output folder"),
    "absolute output path": Case(
        validate("outputs.files=[{path: '<tmp>/elsewhere/{stem}.npz'}]"),
        "outside the output folder",
        absent=("out", "elsewhere"),
    ),
    "{parent} that is ..": Case(
        validate("inputs=<in>/no_meshes/../good.ply", "outputs.files=[{path: '{parent}/{stem}.npz'}]"),
        "output '{parent}/{stem}.npz' of step 'hht': ",
    ),
    "{name} that escapes": Case(
        validate("name=../../n", "outputs.files=[{path: '{name}_{stem}.npz'}]"), "outside the output folder"
    ),
    "allow_outside opts in": Case(
        run("outputs.allow_outside=true", "outputs.files=[{path: '../side/{stem}.npz'}]"),
        "",
        0,
        (),
        check=_written("good.npz", "side"),
    ),
    "user's file under an output name": Case(
        run(),
        "exists and hht3d did not write it",
        absent=(),
        setup=_user_file("out/good_hht.npz"),
        check=_kept("out/good_hht.npz"),
    ),
    "validate notes a user's file under an output name": Case(
        validate(),
        "",
        0,
        (),
        setup=_user_file("out/good_hht.npz"),
        check=_noted("good_hht.npz: exists and hht3d did not"),
    ),
    "--overwrite replaces it": Case(
        (*run(), "--overwrite"), "", 0, (), setup=_user_file("out/good_hht.npz"), check=_replaced("out/good_hht.npz")
    ),
    "--resume does not trust a 0-byte output": Case(
        (*run(), "--resume"),
        "exists and hht3d did not write it",
        absent=(),
        before=(run(),),
        setup=_truncate("out/good_hht.npz"),
    ),
    "--resume --overwrite redoes it": Case(
        (*run(), "--resume", "--overwrite"),
        "",
        0,
        (),
        before=(run(),),
        setup=_truncate("out/good_hht.npz"),
        check=_written("good_hht.npz"),
    ),
    "outputs are never inputs": Case(
        run("inputs=<tmp>/scans", SCANS, PLY_OUTPUT),
        "",
        0,
        (),
        setup=_scans_run_once,
        check=_only_inputs("good.ply", "scan[1].ply"),
    ),
    "two pipelines share a summary": Case(
        run(SUMMARY, "inputs=<in>/huge.ply"),
        "",
        0,
        (),
        before=(run(SUMMARY),),
        check=_summary_rows("good.ply", "huge.ply"),
    ),
    "format spec in a placeholder": Case(
        validate("outputs.files=[{path: '{stem:>9999999999}.npz'}]"), "has a format spec or conversion"
    ),
    "conversion in a placeholder": Case(
        validate("outputs.files=[{path: '{stem!r}.npz'}]"), "has a format spec or conversion"
    ),
    "248-byte output name": Case(
        run(f"outputs.files=[{{path: '{LONG}_hht.npz'}}]"), "", 0, (), check=_written(f"{LONG}_hht.npz")
    ),
    "300-byte output name": Case(
        run(f"outputs.files=[{{path: '{'n' * 296}.npz'}}]"), "is 300 bytes long; the limit is 255"
    ),
    "NUL in an output name": Case(run('outputs.files=[{path: "a\\0{stem}.npz"}]'), "holds a control character"),
    # file:// output folders and inputs are local paths, with every local rule
    "file:// folder, path leaving it": Case(
        validate(FILE_URL, "outputs.files=[{path: '../sentinel/{stem}_hht.npz'}]"),
        "outside the output folder",
        absent=("out", "sentinel"),
    ),
    "file:// folder, {name} leaving it": Case(
        validate(FILE_URL, "name=../../n", "outputs.files=[{path: '{name}.npz'}]"), "outside the output folder"
    ),
    "file:// folder, user's file kept": Case(
        run(FILE_URL),
        "exists and hht3d did not write it",
        absent=(),
        setup=_user_file("out/good_hht.npz"),
        check=_kept("out/good_hht.npz"),
    ),
    "file:// folder and input, manifest and stale parts": Case(
        run(FILE_URL, "inputs=file://<in>/good.ply"), "", 0, (), setup=_dead_part, check=_recorded("good_hht.npz")
    ),
    # the manifest is untrusted input
    "planted manifest naming a file outside": Case(
        run("outputs.allow_outside=true", "outputs.files=[{path: '../sentinel/{stem}_hht.npz'}]"),
        "exists and hht3d did not write it",
        absent=(),
        check=_kept("sentinel/good_hht.npz"),
        setup=_manifest('{"files": {"../sentinel/good_hht.npz": "<mine>"}}', user="sentinel/good_hht.npz"),
    ),
    "allow_outside into a missing folder keeps a user's file": Case(
        run("outputs.allow_outside=true", "outputs.files=[{path: '../side/{stem}_hht.npz'}]"),
        "exists and hht3d did not write it",
        absent=("out",),
        setup=_user_file("side/good_hht.npz"),
        check=_kept("side/good_hht.npz"),
    ),
    "path through a missing subfolder keeps a user's file": Case(
        run("outputs.files=[{path: 'sub/../{stem}_hht.npz'}]"),
        "exists and hht3d did not write it",
        absent=(),
        setup=_user_file("out/good_hht.npz"),
        check=_kept("out/good_hht.npz"),
    ),
    **{
        f"manifest {what}, user's file kept": Case(
            run(),
            "exists and hht3d did not write it",
            absent=(),
            setup=_manifest(text, user="out/good_hht.npz"),
            check=_kept("out/good_hht.npz"),
        )
        for what, text in MALFORMED.items()
    },
    "manifest with a malformed entry, replaced": Case(
        run(), "", 0, (), setup=_manifest('{"files": {"x.npz": [1]}}'), check=_recorded("good_hht.npz")
    ),
    # the lock file
    "lock file a link to a file outside": Case(
        run(),
        "lock file is a link or not a regular file",
        absent=("victim",),
        setup=_lock_file(lambda lock, tmp: lock.symlink_to(tmp / "victim")),
    ),
    "lock file a FIFO": Case(
        run(),
        "lock file is a link or not a regular file",
        absent=(),
        setup=_lock_file(lambda lock, tmp: os.mkfifo(lock)),
    ),
    # a folder swapped for a link between the checks and the write
    "subfolder swapped for a link after the checks": Case(
        run("outputs.files=[{path: 'sub/{stem}_hht.npz'}]"),
        "outside the output folder",
        absent=(),
        setup=_folder_and_user_file,
        fault=_swapped_after_checks,
        check=_kept("elsewhere/good_hht.npz"),
    ),
}


@pytest.mark.parametrize("name", CASES)
def test_bad_input(name, inputs, tmp_path, capfd, monkeypatch):
    run_case(CASES[name], inputs, tmp_path, capfd, monkeypatch)


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


@pytest.mark.parametrize(
    "sets",
    [
        (),
        ("outputs.files=[{path: '../../x_{stem}.npz'}]",),
        ("outputs.files=[{path: '{name}.npz'}]", "name=../n"),
        ("outputs.folder=<in>", "outputs.files=[{path: '{stem}.ply'}]"),
    ],
    ids=["a run", "escaping path", "escaping name", "over its input"],
)
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
