"""Dataset runs: a corrupt file is reported, the others finish, nothing is half-written."""
import json
import shutil

import numpy as np

from conftest import assert_same_hht, hht_arrays_from_ply
from hht3d import Surface, load
from hht3d.dataset import run_dataset
from hht3d.hht import hht
from hht3d.signals import mean_curvature
from hht3d.io import write_ply
from meshes import icosphere


def _make_inputs(folder):
    folder.mkdir()
    v, f = icosphere(3)
    for i, scale in enumerate([1.0, 2.0]):
        bumpy = scale * v * (1 + 0.04 * np.sin((5 + i) * v[:, [0]]))
        write_ply(folder / f"good{i}.ply", Surface(bumpy, f))
    (folder / "corrupt.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n")
    (folder / "three_points.xyz").write_text("0 0 0\n1 0 0\n0 1 0\n")
    return folder


def test_corrupt_file_is_reported_and_others_finish(tmp_path):
    inputs = _make_inputs(tmp_path / "in")
    out = tmp_path / "out"
    rows = run_dataset(inputs, out, scheduler="synchronous", progress=False,
                       emd_options={"max_imfs": 2}, riesz_tasks=2)
    status = {r.source.rsplit("/", 1)[-1]: r for r in rows}
    assert status["good0.ply"].status == status["good1.ply"].status == "ok"
    assert status["good0.ply"].imfs == 2 and status["good0.ply"].vertices == 642
    bad = status["corrupt.ply"]
    assert bad.status == "failed" and bad.step == "load" and "not a readable PLY" in bad.error
    tiny = status["three_points.xyz"]
    assert tiny.status == "failed" and "at least 4" in tiny.error
    produced = sorted(p.name for p in out.iterdir())
    assert produced == ["good0_hht.npz", "good0_hht.ply", "good1_hht.npz", "good1_hht.ply",
                        "summary.csv", "summary.json"]  # nothing for the failures, no temp files
    summary = json.loads((out / "summary.json").read_text())
    assert [r["status"] for r in summary] == [status[k].status for k in
                                              [r["source"].rsplit("/", 1)[-1] for r in summary]]
    # each file holds its own input's HHT, as the Python API computes it in memory
    for name in ("good0", "good1"):
        surface = load(inputs / f"{name}.ply")
        expected = hht(surface, mean_curvature(surface), emd_options={"max_imfs": 2})
        with np.load(out / f"{name}_hht.npz") as saved:
            assert_same_hht(saved, expected)
        assert_same_hht(hht_arrays_from_ply(load(out / f"{name}_hht.ply", clean=False).attributes), expected)


def test_resume_skips_complete_items(tmp_path):
    inputs = _make_inputs(tmp_path / "in")
    for name in ("corrupt.ply", "three_points.xyz"):
        (inputs / name).unlink()
    out = tmp_path / "out"
    run_dataset(inputs, out, scheduler="synchronous", progress=False, emd_options={"max_imfs": 1})
    (out / "good1_hht.npz").unlink()
    rows = run_dataset(inputs, out, scheduler="synchronous", progress=False, resume=True,
                       emd_options={"max_imfs": 1})
    assert [r.status for r in rows] == ["skipped", "ok"]
    shutil.rmtree(out)
