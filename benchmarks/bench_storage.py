"""Object-storage benchmark (not a test): the same dataset from local disk and from an S3 server.

The 8-model dataset of ``bench_graph.py`` (../shared/data: meshes from 2.9k to
62k vertices and a real 40k-point scan; HHT of the mean-curvature signal with
the default options, .ply and .npz outputs) runs on one ``dask.distributed``
cluster of 2 single-threaded workers, each a separate process in its own
empty folder (``tests/servers.py``), in one run:

* **local**: inputs and outputs are local paths (the workers read and write
  this machine's disk);
* **s3**: inputs ``s3://bench/scans/*.ply`` and outputs ``s3://bench/out`` on
  a moto S3 server on 127.0.0.1; the workers download each input to a
  temporary file and upload each output.

The paths run alternately (local, s3, s3, local, ... with ``--repeats``), and
each path's time is its fastest run.  Both get the files in the same order (by
name, the order of the ``s3://`` glob), which sets the order Dask starts them
in.  Reported: the wall-time ratio s3/local (target <= 1.10), the bytes each
model moves (input downloaded + outputs uploaded), the items' task seconds and
each worker's peak memory per run (VmHWM, reset before each run through
``/proc/self/clear_refs``).  Results: ``benchmarks/results/storage.json``
and ``storage.md``.

Usage::

    python benchmarks/bench_storage.py [--repeats 2]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from common import ROOT, machine, model_path, table, write_results

sys.path.insert(0, str(ROOT / "tests"))

DATASET = ["sphere_oct4098", "spot", "spacetime_face_neutral", "rocker_arm", "bunny_zipper", "nefertiti",
           "office_kinect_colored", "bunny_scan_bun000"]
BUCKET = "bench"
TARGET = 1.10


def _reset_peak() -> None:
    Path("/proc/self/clear_refs").write_text("5")  # VmHWM := VmRSS (Linux >= 4.0)


def _peak_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def _timed(client, inputs, out, options) -> dict:
    from hht3d.dataset import run_dataset

    client.run(_reset_peak)
    start = time.perf_counter()
    rows = run_dataset(inputs, out, address=client.scheduler.address, progress=False, **options)
    seconds = time.perf_counter() - start
    peaks = client.run(_peak_mb)
    return {"seconds": seconds, "rows": {Path(r.source).stem: r for r in rows},
            "task_seconds": sum(r.seconds or 0.0 for r in rows),
            "worker_peak_mb": sorted(round(v, 1) for v in peaks.values())}


def _listed(values) -> str:
    return ", ".join(f"{v:.1f}" for v in values)


def main() -> None:
    import fsspec
    from distributed import Client
    from helpers.servers import dask_cluster, s3_server

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=2, help="runs of each path (alternating)")
    args = parser.parse_args()
    missing = [name for name in DATASET if model_path(name) is None]
    if missing:
        sys.exit(f"missing models in ../shared/data: {missing}")
    paths = sorted((model_path(name) for name in DATASET), key=lambda p: p.name)  # the s3 glob's order
    runs = {"local": [], "s3": []}
    with s3_server() as endpoint, dask_cluster(2) as (address, _), Client(address) as client, \
            tempfile.TemporaryDirectory() as local_out:
        storage_options = {"client_kwargs": {"endpoint_url": endpoint}}
        fs = fsspec.filesystem("s3", **storage_options)
        fs.mkdir(BUCKET)
        for path in paths:
            fs.put_file(str(path), f"{BUCKET}/scans/{path.name}")
        from hht3d.dataset import run_dataset

        run_dataset([paths[1]], local_out, address=address, progress=False)  # warm-up: imports on the workers
        order = [name for i in range(args.repeats) for name in (("local", "s3") if i % 2 == 0 else ("s3", "local"))]
        for name in order:
            if name == "local":
                runs["local"].append(_timed(client, paths, local_out, {}))
            else:
                runs["s3"].append(_timed(client, f"s3://{BUCKET}/scans/*.ply", f"s3://{BUCKET}/out",
                                         {"storage_options": storage_options}))
            print(f"{name}: {runs[name][-1]['seconds']:.1f} s", file=sys.stderr, flush=True)
        fs.invalidate_cache()
        sizes = {Path(p).name: fs.info(p)["size"] for p in fs.find(BUCKET)}
    best = {name: min(r["seconds"] for r in results) for name, results in runs.items()}
    ratio = best["s3"] / best["local"]
    models = []
    for path in paths:
        stem, row = path.stem, runs["s3"][0]["rows"][path.stem]
        down, up = sizes[path.name], sizes.get(f"{stem}_hht.ply", 0) + sizes.get(f"{stem}_hht.npz", 0)
        models.append({"model": stem, "status": row.status, "vertices": row.vertices, "imfs": row.imfs,
                       "downloaded_bytes": down, "uploaded_bytes": up,
                       "task_seconds": {k: [round(r["rows"][stem].seconds or 0.0, 2) for r in v]
                                        for k, v in runs.items()}})
    records = {"machine": machine(), "dataset": DATASET, "repeats": args.repeats, "order": order,
               "seconds": {k: [round(r["seconds"], 2) for r in v] for k, v in runs.items()},
               "best_seconds": best, "ratio_s3_over_local": ratio, "target": TARGET,
               "task_seconds": {k: [round(r["task_seconds"], 2) for r in v] for k, v in runs.items()},
               "worker_peak_mb": {k: [r["worker_peak_mb"] for r in v] for k, v in runs.items()}, "models": models}
    rows = [[m["model"], m["status"], m["vertices"], m["imfs"], f"{m['downloaded_bytes'] / 1e6:.2f}",
             f"{m['uploaded_bytes'] / 1e6:.2f}", " / ".join(map(str, m["task_seconds"]["local"])),
             " / ".join(map(str, m["task_seconds"]["s3"]))] for m in models]
    peaks = "; ".join(f"{k}: " + ", ".join(f"{p[0]:.0f} / {p[1]:.0f}" for p in v)
                      for k, v in records["worker_peak_mb"].items())
    markdown = "\n".join([
        "# Object-storage benchmark", "",
        f"Machine: {records['machine']['platform']}; {records['machine']['cpus']} CPUs; load average at end "
        f"{records['machine']['load_average']}; backend `{records['machine']['backend']}`.  Generated by "
        "`python benchmarks/bench_storage.py`.", "",
        "The 8-model dataset of `bench_graph.py` (HHT of the mean-curvature signal, default options, .ply + .npz "
        "outputs) on a `dask.distributed` cluster of 2 single-threaded workers in empty folders of their own: "
        "local paths against `s3://` URLs on a moto S3 server on 127.0.0.1 (workers download and upload "
        "themselves).", "",
        table(["model", "status", "#V", "#IMFs", "downloaded MB", "uploaded MB", "task s, local runs",
               "task s, s3 runs"], rows), "",
        "*task s*: the item's task run times summed (load, signal, EMD, Riesz, spectra, writes; with s3 the "
        "download is in load and the upload in the writes).", "",
        f"Wall time (runs in order {', '.join(order)}): local {_listed(records['seconds']['local'])} s, "
        f"s3 {_listed(records['seconds']['s3'])} s; fastest s3 / fastest local = **{ratio:.3f}** "
        f"(target <= {TARGET:.2f}).  Task seconds summed over the dataset: local "
        f"{_listed(records['task_seconds']['local'])}, s3 {_listed(records['task_seconds']['s3'])}.",
        "",
        f"Peak memory of the two workers per run (MB, VmHWM): {peaks}.", ""])
    for path in write_results("storage", records, markdown):
        print(path)


if __name__ == "__main__":
    main()
