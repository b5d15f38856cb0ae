"""Reading a large LAZ with hht3d's reader (hht3d.io.las.read_las): memory relative to the arrays it keeps,
and points per second, against the issue's targets (<= 1.3x the kept arrays, >= 5M points/s).

``python -m benchmarks.bench_las [--points 10000000] [--folder /tmp]`` writes a synthetic point-format-3
LAZ (a wavy terrain at 1 mm scale, 10^6 m offsets, intensity, classes, returns, GPS time, RGB) with laspy,
then in a fresh subprocess decodes it with laspy alone (the baseline, same run) and reads it once with
hht3d: wall time, and the peak resident memory above the process's
resident memory just before the read (VmHWM after resetting it), divided by the bytes of the kept arrays.
Prints one line of figures; the file is left in ``--folder`` for a rerun.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.common import reset_peak, status_mb


def write_laz(path: Path, points: int) -> None:
    """A synthetic format-3 LAZ of ``points`` points, written in chunks of 10^6."""
    import laspy

    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = np.array([0.001] * 3), np.array([5e5, 5.4e6, 0.0])
    rng = np.random.default_rng(0)
    with laspy.open(str(path), mode="w", header=header) as writer:
        for start in range(0, points, 1_000_000):
            n = min(1_000_000, points - start)
            record = laspy.ScaleAwarePointRecord.zeros(n, header=header)
            x, y = rng.uniform(0, 2000, n), rng.uniform(0, 2000, n)
            record.x, record.y = 5e5 + x, 5.4e6 + y
            record.z = 10 * np.sin(x / 50) * np.cos(y / 80) + rng.normal(0, 0.05, n)
            record.intensity = rng.integers(0, 65535, n)
            record.classification = rng.choice([1, 2, 6], n)
            record.return_number, record.number_of_returns = np.ones(n, np.uint8), np.ones(n, np.uint8)
            record.gps_time = start + np.arange(n) * 1e-5
            for band in ("red", "green", "blue"):
                setattr(record, band, rng.integers(0, 65535, n))
            writer.write_points(record)


def measure(path: Path) -> None:
    """Decode ``path`` with laspy alone, then read it once with hht3d; print points, hht3d's seconds, peak
    above baseline (MB), kept MB, attributes and laspy's seconds."""
    import laspy

    from hht3d.io.las import CHUNK_POINTS, read_las

    start = time.perf_counter()
    with laspy.open(str(path)) as reader:
        for _ in reader.chunk_iterator(CHUNK_POINTS):
            pass
    decode = time.perf_counter() - start
    reset_peak()
    before = status_mb("VmRSS")
    start = time.perf_counter()
    data = read_las(path)
    seconds = time.perf_counter() - start
    peak = status_mb("VmHWM") - before
    kept = sum(v.nbytes for v in [data["vertices"], data["colors"], *data["attributes"].values()])
    print(len(data["vertices"]), seconds, peak, kept / 2**20, len(data["attributes"]), decode)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000_000)
    parser.add_argument("--folder", type=Path, default=Path("/tmp"))
    parser.add_argument("--measure", type=Path, help=argparse.SUPPRESS)  # the subprocess's part
    args = parser.parse_args()
    if args.measure:
        return measure(args.measure)
    path = args.folder / f"bench_las_{args.points}.laz"
    if not path.exists():
        start = time.perf_counter()
        part = path.with_name(f"{path.stem}.part.laz")  # a run stopped while writing leaves no file
        write_laz(part, args.points)
        part.rename(path)
        print(f"wrote {path} ({path.stat().st_size / 2**20:.0f} MB) in {time.perf_counter() - start:.1f} s")
    out = subprocess.run(
        [sys.executable, "-m", "benchmarks.bench_las", "--measure", str(path)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    points, seconds, peak, kept, attributes, decode = int(out[0]), *map(float, out[1:4]), int(out[4]), float(out[5])
    print(
        f"{points:,} points, {attributes} attributes + xyz + RGB: {seconds:.2f} s = {points / seconds / 1e6:.2f} M "
        f"points/s; kept arrays {kept:.0f} MB ({kept * 2**20 / points:.0f} B/point), peak above baseline "
        f"{peak:.0f} MB = {peak / kept:.2f}x the kept arrays; laspy + lazrs decoding alone {decode:.2f} s = "
        f"{points / decode / 1e6:.2f} M points/s"
    )


if __name__ == "__main__":
    main()
