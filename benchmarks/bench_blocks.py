"""A point cloud's robust Laplacian by blocks: in child processes (hht3d.geometry.block_processes, one per
core) against one process, in the same run, on real scans and igea's 1M-point copy.

``python -m benchmarks.bench_blocks [--models dragon_vrip bunny_scans_merged] [--pairs 3]`` builds each
cloud's Laplacian ``--pairs`` times each way, in turn (one process, then the children; a fresh worker
process each time, so that neither inherits the other's heap), and reports the median seconds of each
way and the median of the pairs' ratios, and whether the two Laplacians are the same to the bit.
``results/scratch/igea_1m_cloud.ply`` (``bench_hht --parts scaling --kinds cloud --keep-meshes``) joins
when present.  Writes ``results/blocks.json`` and ``results/blocks.md``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import sys
import time
from pathlib import Path

from benchmarks.common import SCRATCH, load_average, log, machine, model_path, table, worker_json, write_results

#: Real scans whose points make clouds of several blocks (``CLOUD_BLOCK`` = 50,000 points).
MODELS = ["dragon_vrip", "bunny_scans_merged"]


def build_once(path: str) -> dict:
    """Worker: the vertices of ``path`` as a cloud, its Laplacian built once; seconds, blocks, a digest."""
    import numpy as np

    import hht3d
    from hht3d.geometry.block_processes import process_count
    from hht3d.geometry.blocks import CLOUD_BLOCK, bisection_blocks
    from hht3d.geometry.operators import point_cloud_operators

    points = np.ascontiguousarray(hht3d.load(path).vertices)
    start = time.perf_counter()
    lap, mass = point_cloud_operators(points)
    seconds = time.perf_counter() - start
    digest = hashlib.sha256(lap.data.tobytes() + lap.indices.tobytes() + mass.tobytes()).hexdigest()
    blocks = len(bisection_blocks(points, CLOUD_BLOCK)) if len(points) > CLOUD_BLOCK else 1
    return {"points": len(points), "blocks": blocks, "processes": process_count(), "seconds": seconds, "digest": digest}


def markdown(records: dict) -> str:
    rows = [
        [
            r["model"],
            f"{r['points']:,}",
            r["blocks"],
            r["processes"],
            f"{r['one_process_s']:.1f}",
            f"{r['children_s']:.1f}",
            f"{r['ratio']:.2f}",
            "yes" if r["same_bits"] else "**no**",
        ]
        for r in records["rows"]
    ]
    meta = records["meta"]
    m = meta["machine"]
    return "\n\n".join(
        [
            "# A point cloud's robust Laplacian by blocks: child processes against one process",
            f"Machine: {m['platform']}, {m['cpus']} CPUs, Python {m['python']}; {meta['pairs']} pairs each, "
            f"medians; 1-minute load before/after {meta['load']}.",
            table(
                ["model", "points", "blocks", "children", "one process s", "children s", "ratio", "same bits"],
                rows,
            ),
            "*Ratio*: the median of the pairs' children / one-process times (each pair run back to back).",
        ]
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=MODELS)
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        print(json.dumps(build_once(args.worker)))
        return 0
    paths = [(name, model_path(name)) for name in args.models]
    paths += [("igea_1m_cloud", SCRATCH / "igea_1m_cloud.ply")]
    load = load_average()
    rows = []
    for name, path in paths:
        if path is None or not Path(path).is_file():
            log(f"skip {name}: not present")
            continue
        runs: dict[str, list[dict]] = {"1": [], "": []}
        for _ in range(args.pairs):
            for setting in runs:
                env = {k: v for k, v in os.environ.items() if k != "HHT3D_BLOCK_PROCESSES"}
                if setting:
                    env["HHT3D_BLOCK_PROCESSES"] = setting
                runs[setting].append(worker_json(__file__, ["--worker", str(path)], env=env))
        one, children = runs["1"], runs[""]
        rows.append(
            {
                "model": name,
                "points": one[0]["points"],
                "blocks": one[0]["blocks"],
                "processes": children[0]["processes"],
                "one_process_s": statistics.median(r["seconds"] for r in one),
                "children_s": statistics.median(r["seconds"] for r in children),
                "ratio": statistics.median(c["seconds"] / o["seconds"] for o, c in zip(one, children)),
                "same_bits": len({r["digest"] for r in one + children}) == 1,
            }
        )
        log(f"{name}: {rows[-1]}")
    records = {"rows": rows, "meta": {"machine": machine(), "pairs": args.pairs, "load": [load, load_average()]}}
    for path in write_results("blocks", records, markdown(records)):
        log(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
