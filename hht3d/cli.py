"""The ``hht3d`` command line.

``hht3d demo``  runs the HHT of the shipped demo model and writes its outputs;
``hht3d info FILE``  prints what a mesh or point cloud holds.

Exit codes: 0 on success; 1 with a one-line ``hht3d: error: ...`` reason for
bad input or a failed step; 2 for bad command-line usage.
"""
from __future__ import annotations

import argparse
import json
import sys
from importlib import resources
from pathlib import Path

from .errors import HHT3DError
from .scheduling import SCHEDULERS

#: The demo model shipped in the package: Keenan Crane's "spot" (CC0).
DEMO_MODEL = "spot.ply"


def demo_model_path() -> Path:
    """Path of the shipped demo model."""
    return Path(str(resources.files("hht3d") / "data" / DEMO_MODEL))


def _demo(args) -> int:
    from . import graph
    from .io import write_colored_ply

    source = demo_model_path()
    out = Path(args.out)
    surface = graph.load(source)
    result = graph.hht(surface, graph.signal(surface, "mean_curvature"),
                       emd_options={"max_imfs": args.max_imfs})
    stem = source.stem
    saved = [graph.save(result, out / f"{stem}_hht.ply"), graph.save(result, out / f"{stem}_hht.npz")]
    result, *paths = graph.compute(result, *saved, scheduler=args.scheduler, workers=args.workers,
                                   address=args.address, progress=not args.quiet)
    fields = {"signal": result.signal, "imf_1": result.imfs[0] if result.n_imfs else result.residue,
              "frequency_1": result.monogenic.frequency[0] if result.n_imfs else None}
    for name, values in fields.items():
        if values is not None:
            paths.append(write_colored_ply(out / f"{stem}_{name}.ply", result.surface, values, name=name))
    spectrum = result.spectrum
    print(f"{source.name}: {result.surface.n_vertices} vertices, {result.n_imfs} IMFs "
          f"(EMD {result.info['emd']['seconds']:.2f} s, {result.info['emd']['factorizations']} factorizations)")
    for k, (freq, energy) in enumerate(zip(spectrum.mean_frequency(), spectrum.imf_energy()), start=1):
        print(f"  IMF {k}: mean frequency {freq:9.3f} rad/unit, energy {energy:.4g}")
    for path in paths:
        print(f"wrote {path}")
    return 0


def _info(args) -> int:
    from .io import load
    from .topology import describe

    info = describe(load(args.file, clean=not args.no_clean))
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        width = max(map(len, info))
        for key, value in info.items():
            print(f"{key:<{width}}  {value}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="hht3d", description="Hilbert–Huang transform on 3D surfaces")
    sub = parser.add_subparsers(dest="command", required=True)

    demo = sub.add_parser("demo", help="HHT of the shipped demo model (spot, CC0)")
    demo.add_argument("--out", default="out/demo", help="output folder (default: out/demo)")
    demo.add_argument("--max-imfs", type=int, default=6, help="most IMFs (default: 6)")
    demo.add_argument("--scheduler", choices=SCHEDULERS, default="threads")
    demo.add_argument("--workers", type=int, default=None)
    demo.add_argument("--address", default=None, help="address of a running dask.distributed scheduler")
    demo.add_argument("--quiet", action="store_true", help="no progress bar")
    demo.set_defaults(run=_demo)

    info = sub.add_parser("info", help="vertices, faces, components, boundary, manifoldness, bounding box")
    info.add_argument("file")
    info.add_argument("--json", action="store_true", help="print JSON")
    info.add_argument("--no-clean", action="store_true", help="describe the file as stored, before cleaning")
    info.set_defaults(run=_info)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except HHT3DError as exc:
        print(f"hht3d: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("hht3d: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
