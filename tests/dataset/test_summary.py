"""Summaries of dataset and pipeline runs (hht3d.dataset.summary): the quality in every row, and the rows of runs
that write one folder at once."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from helpers.datasets import _make_inputs
from helpers.processes import PIPELINE, _env, _recorded
from hht3d.dataset import run_dataset


def test_summary_rows_carry_the_quality(tmp_path):
    inputs = _make_inputs(tmp_path / "in")
    rows = run_dataset(
        inputs / "good0.ply",
        tmp_path / "out",
        scheduler="synchronous",
        progress=False,
        max_imfs=2,
        riesz_tasks=1,
    )
    (row,) = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert row["energy_ratio"] == rows[0].energy_ratio > 0 and isinstance(row["warnings"], list)
    assert (
        "energy_ratio,orthogonality_index,io_leaking,io_cancelling,warnings"
        in (tmp_path / "out" / "summary.csv").read_text()
    )


@pytest.mark.slow  # real CLI processes
def test_two_runs_into_one_folder_at_once_keep_each_others_summary_rows(job):
    """Different pipelines writing one folder at the same time: summary.json ends with every input's row."""
    out = job / "out"
    for k in range(2):
        (job / f"p{k}.yaml").write_text(
            PIPELINE.format(inputs=job / "scans" / f"s{k}.ply", out=out).replace('    - {path: "{stem}_hht.png"}\n', "")
        )
    runs = [
        subprocess.Popen(
            [sys.executable, "-m", "hht3d", "run", str(job / f"p{k}.yaml"), "--quiet", "--scheduler", "synchronous"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=job,
            env=_env(),
        )
        for k in range(2)
    ]
    for proc in runs:
        _, stderr = proc.communicate(timeout=120)
        assert proc.returncode == 0, stderr
    rows = json.loads((out / "summary.json").read_text())
    assert sorted(Path(r["source"]).name for r in rows) == ["s0.ply", "s1.ply"]
    assert sorted(_recorded(out)) == ["s0_hht.npz", "s1_hht.npz", "summary.csv", "summary.json"]


@pytest.mark.parametrize(
    ("recorded", "solver"),
    [("superlu+chebyshev", "superlu"), ("chebyshev+pardiso", "pardiso"), ("chebyshev", None), ("superlu", "superlu")],
)
def test_the_solver_advice_reads_the_solver_out_of_what_applied_the_filters(recorded, solver):
    """Iterative filtering records ``chebyshev`` joined to the solver; the summary's slow-solver advice takes the
    solver (a 362k-point scan's pipeline failed on 'pardiso+chebyshev' as a backend name)."""
    from types import SimpleNamespace

    from hht3d.dataset.summary import _backend_of
    from hht3d.linalg.estimate import slow_fallback

    assert _backend_of(SimpleNamespace(info={"emd": {"backend": recorded}})) == solver
    if solver == "superlu":
        assert "superlu is a slow sparse solver for 1,000,000 vertices" in slow_fallback(10**6, solver)
