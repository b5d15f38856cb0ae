"""Datasets and pipelines in object storage, on a Dask cluster whose workers share no files.

A real S3-compatible server (moto's ThreadedMotoServer on 127.0.0.1, and the
independent s3rver where Node.js is installed: every test runs on each) and a
real ``dask.distributed`` scheduler with two workers, each a separate process
started in its own empty temporary folder (:mod:`servers`).  The workers get
URLs and storage_options, never the client's files, and must leave no
temporary copy behind.  Oracles: the same run on local files (to 1e-12), the
objects in the bucket, exit codes and the lines printed.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("s3fs", reason="the object-storage tests need s3fs (pip install -e '.[dev]')")
pytest.importorskip("moto.server", reason="the object-storage tests need moto[server] (pip install -e '.[dev]')")

import fsspec  # noqa: E402
from plyfile import PlyData  # noqa: E402

from helpers.models import shipped_model_path  # noqa: E402
from helpers.secrets import forms_found  # noqa: E402
from helpers.servers import FAKE_CREDENTIALS, ROOT, S3_SERVERS, dask_cluster, s3_server, worker_leftovers  # noqa: E402
from hht3d.cli import main  # noqa: E402
from hht3d.dataset import run_dataset  # noqa: E402
from hht3d.errors import InputError, OutputError  # noqa: E402

BUCKET = "hht"
MODELS = {"spot.ply": "spot.ply", "sphere.ply": "sphere_oct4098.ply"}
CORRUPT = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\nnot a number\n"
EMD = {"max_imfs": 2}  # the EMD settings these runs pass by name (**EMD)
#: A recognisable secret: it must appear in nothing the runs print or write.
SECRET = "hht3dSECRETvalue0123456789abcdef"
TIMEOUT = 120


@pytest.fixture(scope="module", params=S3_SERVERS)
def store(request):
    """``(endpoint, storage_options, fs)`` of an S3 server holding the scans: moto, and s3rver (an
    independent implementation, npm) where Node exists; the test ids name the server that ran."""
    with s3_server(request.param) as endpoint:
        options = {"client_kwargs": {"endpoint_url": endpoint}}
        fs = fsspec.filesystem("s3", **options)
        fs.mkdir(BUCKET)
        for key, model in MODELS.items():
            fs.put_file(str(shipped_model_path(model)), f"{BUCKET}/scans/{key}")
        fs.pipe_file(f"{BUCKET}/mixed/bad.ply", CORRUPT)
        yield endpoint, options, fs


@pytest.fixture(scope="module")
def cluster():
    """``(address, folders)`` of a scheduler and two workers in empty folders of their own."""
    with dask_cluster(2) as running:
        yield running


@pytest.fixture(scope="module")
def local_scans(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scans")
    for key, model in MODELS.items():
        (folder / key).write_bytes(shipped_model_path(model).read_bytes())
    return folder


@pytest.fixture(scope="module")
def remote_run(store, cluster):
    """The dataset of the two scans and the corrupt object, from s3:// to s3:// on the cluster."""
    _, options, _ = store
    rows = run_dataset(
        [f"s3://{BUCKET}/scans/*.ply", f"s3://{BUCKET}/mixed/bad.ply"],
        f"s3://{BUCKET}/out",
        address=cluster[0],
        storage_options=options,
        progress=False,
        **EMD,
    )
    return {Path(r.source).name: r for r in rows}


def _arrays(data: bytes, suffix: str) -> dict:
    """The arrays of a saved result: an npz's, or a PLY's vertex properties."""
    import io

    if suffix == ".npz":
        with np.load(io.BytesIO(data)) as npz:
            return {k: npz[k] for k in npz.files}
    vertex = PlyData.read(io.BytesIO(data))["vertex"].data
    return {k: np.asarray(vertex[k], dtype=np.float64) for k in vertex.dtype.names}


def assert_same_outputs(remote: bytes, local: bytes, suffix: str) -> None:
    a, b = _arrays(remote, suffix), _arrays(local, suffix)
    assert a.keys() == b.keys()
    for key in a:
        if not np.issubdtype(b[key].dtype, np.number):  # the Laplacian's name
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
            continue
        scale = max(1.0, float(np.max(np.abs(b[key])))) if b[key].size else 1.0
        np.testing.assert_allclose(a[key], b[key], rtol=0, atol=1e-12 * scale, err_msg=key)


def test_dataset_from_s3_to_s3_equals_the_local_run_and_isolates_a_corrupt_object(
    store, cluster, remote_run, local_scans, tmp_path
):
    _, _, fs = store
    assert {k: r.status for k, r in remote_run.items()} == {"spot.ply": "ok", "sphere.ply": "ok", "bad.ply": "failed"}
    bad = remote_run["bad.ply"]
    assert bad.step == "load" and "s3://hht/mixed/bad.ply" in bad.error and bad.outputs == ()
    local = {
        Path(r.source).name: r
        for r in run_dataset(local_scans, tmp_path, scheduler="synchronous", progress=False, **EMD)
    }
    fs.invalidate_cache()
    written = sorted(Path(p).name for p in fs.ls(f"{BUCKET}/out"))
    assert written == [
        ".hht3d-manifest.json",
        "sphere_hht.npz",
        "sphere_hht.ply",
        "spot_hht.npz",
        "spot_hht.ply",
        "summary.csv",
        "summary.json",
    ]
    for key in MODELS:
        assert remote_run[key].vertices == local[key].vertices
        for suffix in (".npz", ".ply"):
            stem = Path(key).stem
            assert_same_outputs(
                fs.cat_file(f"{BUCKET}/out/{stem}_hht{suffix}"), (tmp_path / f"{stem}_hht{suffix}").read_bytes(), suffix
            )
    summary = json.loads(fs.cat_file(f"{BUCKET}/out/summary.json"))
    assert {Path(r["source"]).name: r["status"] for r in summary} == {
        "spot.ply": "ok",
        "sphere.ply": "ok",
        "bad.ply": "failed",
    }
    assert worker_leftovers(cluster[1]) == [], "the workers' temporary copies must be removed"


def test_a_resumed_run_skips_the_outputs_that_exist_remotely(store, cluster, remote_run):
    _, options, fs = store
    fs.invalidate_cache()
    before = {p: fs.info(p)["LastModified"] for p in fs.ls(f"{BUCKET}/out") if p.endswith((".ply", ".npz"))}
    rows = run_dataset(
        [f"s3://{BUCKET}/scans/*.ply", f"s3://{BUCKET}/mixed/bad.ply"],
        f"s3://{BUCKET}/out",
        address=cluster[0],
        storage_options=options,
        progress=False,
        resume=True,
        **EMD,
    )
    by_name = {Path(r.source).name: r for r in rows}
    assert [by_name[k].status for k in ("spot.ply", "sphere.ply", "bad.ply")] == ["skipped", "skipped", "failed"]
    assert (by_name["spot.ply"].vertices, by_name["spot.ply"].imfs) == (2930, 2)
    assert (by_name["sphere.ply"].vertices, by_name["sphere.ply"].imfs) == (4098, 2)
    fs.invalidate_cache()
    assert {p: fs.info(p)["LastModified"] for p in before} == before


PIPELINE = """\
version: 1
storage_options:
  client_kwargs: {{endpoint_url: "{endpoint}"}}
inputs: {inputs}
steps:
  - op: signal
    params: {{kind: mean_curvature}}
  - op: hht
    params: {{max_imfs: 2}}
outputs:
  folder: {folder}
  files:
    - {{path: "{{stem}}_hht.npz"}}
    - {{path: "{{stem}}_frequency_1.ply", field: frequency_1}}
"""


def _cli(*args, env=None) -> subprocess.CompletedProcess:
    """``hht3d ARGS`` in a subprocess with this checkout on PYTHONPATH."""
    return subprocess.run(
        [sys.executable, "-m", "hht3d", *args],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
        env={**os.environ, "PYTHONPATH": str(ROOT), **(env or {})},
    )


def test_a_yaml_pipeline_from_s3_to_s3_equals_the_local_run(store, cluster, local_scans, tmp_path):
    endpoint, _, fs = store
    remote = tmp_path / "remote.yaml"
    remote.write_text(
        PIPELINE.format(endpoint=endpoint, inputs=f"s3://{BUCKET}/scans/", folder=f"s3://{BUCKET}/yaml-out")
    )
    run = _cli("run", str(remote), "--address", cluster[0], "--quiet")
    assert run.returncode == 0, run.stderr
    assert "s3://hht/scans/spot.ply: ok" in run.stdout
    local = tmp_path / "local.yaml"
    local.write_text(PIPELINE.format(endpoint=endpoint, inputs=str(local_scans), folder=str(tmp_path / "out")))
    assert main(["run", str(local), "--scheduler", "synchronous", "--quiet"]) == 0
    for key in MODELS:
        stem = Path(key).stem
        for name in (f"{stem}_hht.npz", f"{stem}_frequency_1.ply"):
            assert_same_outputs(
                fs.cat_file(f"{BUCKET}/yaml-out/{name}"), (tmp_path / "out" / name).read_bytes(), Path(name).suffix
            )
    assert json.loads(fs.cat_file(f"{BUCKET}/yaml-out/summary.json"))[0]["status"] == "ok"


def test_a_missing_bucket_is_one_line_at_validate_and_before_computing(store, tmp_path):
    endpoint, options, _ = store
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        PIPELINE.format(endpoint=endpoint, inputs=f"s3://{BUCKET}/scans/spot.ply", folder="s3://no-such-bucket/out")
    )
    check = _cli("validate", str(pipeline))
    assert check.returncode == 1 and check.stdout == ""
    assert check.stderr.count("\n") == 1 and "bucket 'no-such-bucket' does not exist" in check.stderr
    with pytest.raises(OutputError, match="no-such-bucket"):
        run_dataset(
            f"s3://{BUCKET}/scans/spot.ply",
            "s3://no-such-bucket/out",
            storage_options=options,
            scheduler="synchronous",
            progress=False,
        )


def test_a_missing_back_end_names_the_pip_command():
    if any(_importable(m) for m in ("gcsfs",)):
        pytest.skip("gcsfs is installed here")
    with pytest.raises(InputError, match=r"pip install 'hht3d\[gcs\]'"):
        run_dataset("gs://bucket/scans/*.ply", "out", scheduler="synchronous", progress=False)


def _importable(module: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(module) is not None


def test_a_secret_never_appears_in_what_runs_print_or_write(store, cluster, tmp_path, capfd):
    endpoint, options, fs = store
    secret_options = {**options, "key": FAKE_CREDENTIALS["AWS_ACCESS_KEY_ID"], "secret": SECRET}  # a key both know
    rows = run_dataset(
        [f"s3://{BUCKET}/scans/spot.ply", f"s3://{BUCKET}/mixed/bad.ply"],
        f"s3://{BUCKET}/secret-out",
        address=cluster[0],
        storage_options=secret_options,
        progress=True,
        **EMD,
    )
    assert [r.status for r in rows] == ["ok", "failed"]
    signed = f"{endpoint}/{BUCKET}/missing.ply?X-Amz-Credential=id&X-Amz-Signature={SECRET}"
    with pytest.raises(InputError) as raised:
        run_dataset(signed, tmp_path / "signed", scheduler="synchronous", progress=False)
    assert "X-Amz-Signature=***" in str(raised.value)
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        PIPELINE.format(endpoint=endpoint, inputs=f"s3://{BUCKET}/mixed/bad.ply", folder=f"s3://{BUCKET}/secret-yaml")
    )
    env = {"AWS_SECRET_ACCESS_KEY": SECRET}  # credentials from the usual place
    runs = [
        _cli("run", str(pipeline), "--address", cluster[0], env=env),
        _cli("validate", str(pipeline), "--set", f"inputs={signed}", env=env),
        _cli("validate", str(pipeline), "--set", f"storage_options.secret={SECRET}"),
    ]
    assert [r.returncode for r in runs] == [1, 1, 1]
    assert "credentials do not belong in a pipeline file" in runs[2].stderr
    captured = capfd.readouterr()
    printed = [captured.out, captured.err] + [r.stdout + r.stderr for r in runs]
    fs.invalidate_cache()
    written = [fs.cat_file(p) for prefix in ("secret-out", "secret-yaml") for p in fs.find(f"{BUCKET}/{prefix}")]
    assert len(written) == 8  # spot's .ply and .npz; summary.json, .csv and manifest of both runs (the YAML one failed)
    written += [p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()]
    written += [p.read_bytes() for folder in cluster[1] for p in folder.rglob("*.log")]
    assert [forms_found(text, SECRET) for text in printed + written] == [[]] * len(printed + written)


def test_a_failed_write_leaves_no_object_and_a_non_atomic_store_gets_a_moved_whole_file(tmp_path):
    from hht3d.io.uploads import write_via

    def half_then_fail(data: bytes, path: Path) -> None:
        path.write_bytes(data[: len(data) // 2])
        raise RuntimeError("killed mid-write")

    memory = fsspec.filesystem("memory")
    with pytest.raises(RuntimeError):
        write_via(half_then_fail, b"x" * 1000, "memory://atomic/out.bin")
    assert not memory.exists("/atomic/out.bin")

    class NonAtomic(fsspec.implementations.memory.MemoryFileSystem):
        protocol = "nonatomic"  # no atomic upload there: a temporary name, then a move

    fsspec.register_implementation("nonatomic", NonAtomic, clobber=True)
    url = "nonatomic://nonatomic/out/result.bin"
    assert write_via(lambda data, path: path.write_bytes(data), b"y" * 1000, url) == url
    store = NonAtomic()
    assert [Path(p).name for p in store.ls("nonatomic://nonatomic/out", detail=False)] == ["result.bin"]
    assert store.cat_file("nonatomic://nonatomic/out/result.bin") == b"y" * 1000


def test_the_cli_reads_and_writes_urls(tmp_path, capsys):
    memory = fsspec.filesystem("memory")
    memory.put_file(str(shipped_model_path("spot.ply")), "/cli/scans/spot.ply")
    assert main(["info", "memory://cli/scans/spot.ply", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["vertices"] == 2930
    assert main(["view", "memory://cli/scans/spot.ply", "--out", "memory://cli/pages/spot.html"]) == 0
    assert capsys.readouterr().out.strip() == "memory://cli/pages/spot.html"
    assert memory.cat_file("/cli/pages/spot.html").lstrip().lower().startswith(b"<!doctype html")


def test_url_inputs_into_a_local_folder_keep_the_local_rules(store, tmp_path):
    """S3 inputs, a local output folder: the manifest records every output with its size and SHA-256,
    resume trusts it, and an output changed since is neither trusted nor replaced without --overwrite."""
    import hashlib

    from hht3d.io.manifest import entries

    _, options, _ = store
    spot, out = f"s3://{BUCKET}/scans/spot.ply", tmp_path / "out"

    def run(**flags):
        return run_dataset(spot, out, storage_options=options, scheduler="synchronous", progress=False, **EMD, **flags)

    assert [r.status for r in run()] == ["ok"]
    recorded = entries(out)
    assert set(recorded) == {"spot_hht.npz", "spot_hht.ply", "summary.json", "summary.csv"}
    npz = (out / "spot_hht.npz").read_bytes()
    assert (recorded["spot_hht.npz"]["size"], recorded["spot_hht.npz"]["sha256"]) == (
        len(npz),
        hashlib.sha256(npz).hexdigest(),
    )
    assert [r.status for r in run(resume=True)] == ["skipped"]
    (out / "spot_hht.ply").write_bytes(b"")  # changed since it was recorded
    with pytest.raises(OutputError, match="hht3d did not write it"):
        run(resume=True)
    assert (out / "spot_hht.ply").read_bytes() == b""
    assert [r.status for r in run(resume=True, overwrite=True)] == ["ok"]
    assert (out / "spot_hht.ply").stat().st_size == entries(out)["spot_hht.ply"]["size"] > 0


def test_a_url_output_folder_resumes_only_what_its_manifest_object_records(store, tmp_path, capsys):
    """A local pipeline writing to s3://: the outputs, then the summary, then a manifest object (the local
    manifest's shape: sizes and SHA-256) and no lock object; --resume skips what the manifest records as it is,
    and redoes an object emptied or changed since."""
    import hashlib

    endpoint, _, fs = store
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        PIPELINE.format(endpoint=endpoint, inputs=str(shipped_model_path("spot.ply")), folder=f"s3://{BUCKET}/resumed")
    )

    def run(*flags) -> str:
        assert main(["run", str(pipeline), "--scheduler", "synchronous", "--quiet", *flags]) == 0
        return capsys.readouterr().out

    run()
    fs.invalidate_cache()
    assert sorted(Path(p).name for p in fs.ls(f"{BUCKET}/resumed")) == [
        ".hht3d-manifest.json",
        "spot_frequency_1.ply",
        "spot_hht.npz",
        "summary.csv",
        "summary.json",
    ]
    files = json.loads(fs.cat_file(f"{BUCKET}/resumed/.hht3d-manifest.json"))["files"]
    for name in ("spot_hht.npz", "spot_frequency_1.ply", "summary.json", "summary.csv"):
        data = fs.cat_file(f"{BUCKET}/resumed/{name}")
        assert (files[name]["size"], files[name]["sha256"]) == (len(data), hashlib.sha256(data).hexdigest())
    assert "spot.ply: skipped (outputs complete), 2930 vertices, 2 IMFs" in run("--resume")
    good = fs.cat_file(f"{BUCKET}/resumed/spot_hht.npz")
    for changed in (b"", b"x" * len(good)):  # emptied, then the same size with other bytes
        fs.pipe_file(f"{BUCKET}/resumed/spot_hht.npz", changed)
        assert "spot.ply: ok" in run("--resume")
        assert fs.cat_file(f"{BUCKET}/resumed/spot_hht.npz") == good


def test_url_output_keys_leaving_the_folder_are_refused(store, tmp_path, capsys):
    endpoint, _, fs = store
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        PIPELINE.format(
            endpoint=endpoint, inputs=str(shipped_model_path("spot.ply")), folder=f"s3://{BUCKET}/confined/U05"
        )
    )
    assert (
        main(
            [
                "validate",
                str(pipeline),
                "--set",
                "name=../../victim",
                "--set",
                "outputs.files=[{path: '{name}/{stem}.npz'}]",
            ]
        )
        == 1
    )
    message = f"s3://{BUCKET}/victim/spot.npz leaves the output folder s3://{BUCKET}/confined/U05"
    assert message in capsys.readouterr().err
    fs.invalidate_cache()
    assert not fs.exists(f"{BUCKET}/victim") and not fs.exists(f"{BUCKET}/confined")


@pytest.mark.parametrize("folder", [f"s3://{BUCKET}/merged", "memory://merged"])
def test_runs_into_one_url_folder_keep_each_others_summary_rows(store, folder):
    from hht3d.dataset import ItemSummary, write_summary

    _, options, _ = store
    options = options if folder.startswith("s3") else None
    write_summary([ItemSummary("a.ply", "ok"), ItemSummary("b.ply", "failed")], folder, "R1", options)
    write_summary([ItemSummary("b.ply", "ok"), ItemSummary("c.ply", "ok")], folder, "R2", options)
    fs, path = fsspec.core.url_to_fs(folder, **(options or {}))
    rows = json.loads(fs.cat_file(f"{path}/summary.json"))
    assert [(r["source"], r["status"]) for r in rows] == [("a.ply", "ok"), ("b.ply", "ok"), ("c.ply", "ok")]
    table = fs.cat_file(f"{path}/summary.csv").decode().splitlines()[1:]
    assert [line.split(",")[:2] for line in table] == [["a.ply", "ok"], ["b.ply", "ok"], ["c.ply", "ok"]]
    assert {v["run"] for v in json.loads(fs.cat_file(f"{path}/.hht3d-manifest.json"))["files"].values()} == {"R2"}


def test_a_conditional_summary_write_keeps_the_rows_of_a_run_that_came_first(store, request):
    """On S3 the summary is written If-Match its ETag: another run's summary written between this run's read
    and its write makes the write fail and be redone from the other run's rows."""
    from hht3d.io.uploads import update_object

    if request.node.callspec.params["store"] == "s3rver":
        pytest.skip(
            "s3rver 3.7 ignores If-Match and If-None-Match: there the last of two runs wins, as on "
            "stores without conditional writes (docs/guide/safety.md)"
        )

    _, options, fs = store
    url = f"s3://{BUCKET}/raced/summary.json"
    fs.pipe_file(url, b"[]")
    seen = []

    def update(old: bytes | None) -> bytes:
        seen.append(old)
        if len(seen) == 1:  # the other run writes after this one read
            fs.pipe_file(url, json.dumps([{"source": "theirs"}]).encode())
        return json.dumps(json.loads(old) + [{"source": "ours"}]).encode()

    update_object(url, update, options)
    assert seen[0] == b"[]" and len(seen) == 2
    assert json.loads(fs.cat_file(url)) == [{"source": "theirs"}, {"source": "ours"}]


def _pickled_graph(*collections) -> bytes:
    """The graph as a scheduler receives it: every task of ``collections``, pickled (this dask has no
    ``dask.base.collections_to_dsk``: each collection's ``__dask_graph__``, merged)."""
    import cloudpickle

    tasks: dict = {}
    for collection in collections:
        tasks.update(dict(collection.__dask_graph__()))
    return cloudpickle.dumps(tasks)


@pytest.mark.parametrize("scheduler", ["synchronous", "threads", "processes", "distributed"])
def test_storage_options_stay_out_of_the_graph_and_every_scheduler_reads_and_writes(store, scheduler):
    """Credentials given as storage_options from Python are not in the task graph in any form
    (the tasks carry a token, :mod:`hht3d.io.sealed`), yet each scheduler's workers (this process,
    pool processes, a LocalCluster's workers) read the scans from and write the results to S3."""
    from hht3d import graph
    from hht3d.dataset.run import dataset_graph

    _, options, fs = store
    secret_options = {**options, "key": "S3RVER", "secret": SECRET}
    out = f"s3://{BUCKET}/sealed-{scheduler}"
    lazy = dataset_graph(f"s3://{BUCKET}/scans/spot.ply", out, storage_options=secret_options, **EMD)
    surface = graph.load(f"s3://{BUCKET}/scans/spot.ply", storage_options=secret_options)
    saved = graph.save(
        graph.hht(surface, graph.signal(surface, "mean_curvature"), max_imfs=2),
        f"{out}/g.npz",
        storage_options=secret_options,
    )
    pickled = _pickled_graph(lazy, saved)
    assert b"Sealed" in pickled  # the tokens are there, standing for the options
    assert forms_found(pickled, SECRET) == [] and forms_found(repr(lazy.dask), SECRET) == []
    rows = run_dataset(
        f"s3://{BUCKET}/scans/spot.ply",
        out,
        scheduler=scheduler,
        workers=2,
        storage_options=secret_options,
        progress=False,
        **EMD,
    )
    assert [r.status for r in rows] == ["ok"], rows[0].error
    fs.invalidate_cache()
    assert {p.rsplit("/", 1)[1] for p in fs.find(f"{BUCKET}/sealed-{scheduler}")} >= {"spot_hht.npz", "spot_hht.ply"}


def test_a_task_whose_storage_options_were_not_shared_says_so():
    """A token no worker received (a graph computed by a client hht3d did not prepare) is one line."""
    from hht3d.io.sealed import Sealed, unsealed

    with pytest.raises(InputError, match="share_storage_options"):
        unsealed(Sealed("0" * 32))
