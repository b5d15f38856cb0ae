"""The ``hht3d`` command line.

``hht3d run PIPELINE.yaml``       validate and run a pipeline (:mod:`hht3d.pipeline`);
``hht3d validate PIPELINE.yaml``  validate it and print the planned graph, running nothing;
``hht3d ops [OP]``                list the operations, their parameters and defaults;
``hht3d info FILE``               what a mesh or point cloud holds;
``hht3d view FILE.npz|FILE.ply``  write the interactive HTML page of a saved result and print its path;
``hht3d info --backends``         which sparse solver runs, and why;
``hht3d demo``                    run the demo pipeline shipped in the package;
``hht3d --version``               the version (:mod:`hht3d.version`).

Every command takes ``-v``/``--verbose``, ``-q``/``--quiet`` and ``--log-level``: the
least important of hht3d's messages shown (:mod:`hht3d.logs`).  Informational ones (memory
and time estimates, the dashboard address) go to stdout beside the results; progress lines,
warnings and errors to stderr, so that a failed run says one line there.

Exit codes: 0 on success; 1 with a one-line ``hht3d: error: ...`` reason for
an invalid pipeline, bad input or a failed step; 2 for bad command-line usage;
130 on SIGINT (Ctrl-C) and 143 on SIGTERM, after a clean stop
(:mod:`hht3d.stopping`).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence, cast

from .errors import HHT3DError, PipelineError, one_line, shown
from .execution import SCHEDULERS
from .io.read import data_path
from .logs import get_logger, log_level, logging_options, showing
from .redaction import redact
from .version import __version__
from .viz.render import UP_AXES, VIEWS
from .viz.viewer import VERTEX_BUDGET

if TYPE_CHECKING:
    from hht3d.pipeline.plan import Pipeline
    from hht3d.pipeline.runner import ItemSummary, OutputFolder  # the runner's own imports

#: The demo model shipped in the package: Keenan Crane's "spot" (CC0).
DEMO_MODEL = "spot.ply"
#: The demo pipeline shipped in the package (also ``pipelines/demo.yaml``).
DEMO_PIPELINE = "demo.yaml"
#: Characters of an error message printed (the values it echoes are cut shorter already).
MAX_MESSAGE = 2000
_LOG = get_logger("hht3d.cli")


def demo_model_path() -> Path:
    """Path of the shipped demo model."""
    return data_path(DEMO_MODEL)


def demo_pipeline_path() -> Path:
    """Path of the shipped demo pipeline."""
    return data_path(DEMO_PIPELINE)


def _plan(path: Path | str, overrides: Sequence[str]) -> Pipeline:
    """The validated pipeline; a ``memory://`` output folder is refused, since its results would
    vanish with this process (from Python, :func:`hht3d.pipeline.run_pipeline` takes one)."""
    from .pipeline import load_pipeline

    plan = load_pipeline(path, overrides)
    if str(plan.folder).lower().startswith("memory://"):
        raise PipelineError(
            f"{path}: outputs.folder {shown(str(plan.folder))} is in this process's memory and "
            "would vanish when the command ends; give a local folder or a bucket"
        )
    return plan


def _row_lines(row: ItemSummary) -> list[str]:
    """How the CLI reports one input: a status line, then its warnings and the files written."""
    size = "".join(
        [
            f", {row.vertices} vertices" if row.vertices is not None else "",
            f", {row.imfs} IMFs" if row.imfs is not None else "",
        ]
    )
    if row.status == "ok":
        quality = (
            f", energy ratio {row.energy_ratio:.3g}, IO {row.orthogonality_index:+.2f}"
            if row.energy_ratio is not None
            else ""
        )
        lines = [f"{row.source}: ok{size}, {row.seconds:.1f} s{quality}"]
    elif row.status == "skipped":
        lines = [f"{row.source}: skipped (outputs complete){size}; not re-run"]
    else:
        lines = [f"{row.source}: FAILED in step {row.step}: {row.error}"]
    lines += [f"  warning: {w}" for w in row.warnings]
    verb = "kept" if row.status == "skipped" else "wrote"
    return lines + [f"  {verb} {path}" for path in row.outputs]


def _not_done(plan: Pipeline, folder: OutputFolder) -> str:
    """The inputs whose outputs are not all done in ``folder`` (an OutputFolder), for a message."""
    left = [redact(str(s)) for s in plan.inputs if not folder.done(plan.output_paths(s))]
    return f"{len(left)} of {len(plan.inputs)} inputs not done" + (f" ({shown(left)})" if left else "")


def _execute(plan: Pipeline, args: argparse.Namespace) -> int:
    from .dataset.summary import summary_paths, write_summary
    from .execution import ClusterLost
    from .pipeline.resources import check_resources, resource_lines
    from .pipeline.runner import failures, output_folder, run_pipeline
    from .stopping import Stopped, clean_stop

    folder = output_folder(plan)
    check_resources(plan)
    for line in resource_lines(plan):
        _LOG.info(line)
    try:  # a stop while the lock is being taken is cleaned too: release_all removes it if it landed
        with folder.lock():  # a URL folder's, for the whole run (released as the block ends, a stop included)
            rows = run_pipeline(
                plan,
                scheduler=args.scheduler,
                workers=args.workers,
                address=args.address,
                progress=False if args.quiet else None,
                resume=args.resume,
                overwrite=args.overwrite,
                summary=False,
                run=folder.run,
                allow_plugins=args.allow_plugins or None,
            )
            for row in rows:
                print(redact("\n".join(_row_lines(row))), flush=True)
            slow = [row for row in rows if row.solver_advice]
            if slow:  # once per run, for its largest input
                _LOG.warning(max(slow, key=lambda row: cast(int, row.vertices)).solver_advice)  # set with the advice
            if plan.summary:
                write_summary(rows, plan.folder, folder.run, plan.storage_options)
                print(redact(f"summary: {', '.join(map(str, summary_paths(plan.folder)))}"))
    except Stopped as stop:
        clean_stop(folder.part_folders(plan.written_paths()))
        print(
            f"hht3d: stopped by {stop}: {_not_done(plan, folder)}; temporary files removed; run again with "
            "--resume to finish",
            file=sys.stderr,
            flush=True,
        )
        sys.stdout.flush()
        os._exit(stop.exit_code)  # worker threads of the stopped run are not waited for
    except ClusterLost as exc:
        raise ClusterLost(f"{exc}; {_not_done(plan, folder)}; run again with --resume to finish") from None
    failed = failures(rows)
    if failed:
        raise PipelineError(f"{len(failed)} of {len(rows)} inputs failed; first: {failed[0]}")
    return 0


def _run(args: argparse.Namespace) -> int:
    return _execute(_plan(args.pipeline, args.set), args)


def _demo(args: argparse.Namespace) -> int:
    return _execute(_plan(demo_pipeline_path(), [f"outputs.folder={json.dumps(args.out)}", *args.set]), args)


def _validate(args: argparse.Namespace) -> int:
    from .errors import OutputError
    from .pipeline.resources import check_resources, resource_lines
    from .pipeline.runner import output_folder

    plan = _plan(args.pipeline, args.set)
    print(redact(plan.describe()))
    for line in resource_lines(plan):
        print(redact(line))
    check_resources(plan)
    try:
        output_folder(plan).check_overwrites(plan.written_paths())
    except OutputError as exc:
        print(redact(f"note: {exc}"))
    print("valid: parameters, inputs and output locations checked, memory estimated; nothing was run")
    return 0


def _ops(args: argparse.Namespace) -> int:
    from .output_formats import FORMATS
    from .pipeline.params import record_params, yaml_text
    from .pipeline.plugins import operation, operations, plugin_sources

    sources = plugin_sources()
    for op in [operation(name, "hht3d ops") for name in args.op] or operations().values():
        takes = ", ".join(f"{s.name}: {'|'.join(s.kinds)}" for s in op.slots)
        source = f"  [plugin: {sources[op.name]}]" if op.name in sources else ""
        print(f"{op.name}({takes}) -> {op.output}{source}\n    {op.summary}")
        width = max((len(p.name) for p in op.params), default=0)
        for p in op.params:
            print(f"    {p.name:<{width}}  {yaml_text(p.default):<10}  {p.describe()} — {p.doc}")
    if not args.op:
        print("\noutputs (outputs.files entries: {from: STEP, path: PATTERN, format: ..., options}):")
        for kind, formats in FORMATS.items():
            for fmt in formats.values():
                options = ", ".join(f"{p.name}={yaml_text(p.default)}" for p in record_params(fmt.options))
                print(f"    {kind:<9} {fmt.name:<12} {fmt.summary}" + (f" [{options}]" if options else ""))
    return 0


def _backends(vertices: int) -> None:
    from .linalg import backend_report, estimate_lines

    statuses, reason = backend_report()
    chosen = next(s.name for s in statuses if s.default)
    print(f"sparse solver: {chosen} ({reason})")
    for s in statuses:
        print(f"  {'*' if s.default else ' '} {s.name:<8} {'available' if s.available else 'missing  '}  {s.detail}")
    print("\n".join(estimate_lines(vertices)))


def _info(args: argparse.Namespace) -> int:
    from .geometry.topology import describe
    from .io import load

    surface = None if args.file is None else load(args.file, clean=not args.no_clean)
    if args.backends:
        _backends(args.vertices if surface is None else surface.n_vertices)
    if surface is None:
        return 0
    info = describe(surface)  # coordinates are bounded at load: values are finite
    if args.json:
        print(json.dumps(info, indent=2, allow_nan=False))
    else:
        width = max(map(len, info))
        for key, value in info.items():
            print(f"{key:<{width}}  {value}")
    return 0


def _view(args: argparse.Namespace) -> int:
    from .io.storage import is_url, local_copy, stem
    from .io.uploads import write_via
    from .viz.viewer import file_html

    out = args.out or (f"{stem(args.file)}.html" if is_url(args.file) else None)
    with local_copy(args.file) as local:  # a URL is read through a temporary copy, a page URL uploaded
        page = write_via(
            file_html, local, out, field=args.field, max_vertices=args.max_vertices, view=args.view, up=args.up
        )
    print(redact(str(page)))
    return 0


def _schema(args: argparse.Namespace) -> int:
    from .io.atomic import atomic_path
    from .pipeline.json_schema import schema_text

    if args.output is None:
        print(schema_text(), end="")
        return 0
    with atomic_path(Path(args.output)) as tmp:
        Path(tmp).write_text(schema_text(), encoding="utf-8")
    print(args.output)
    return 0


def _add_run_options(parser: argparse.ArgumentParser, *, running: bool = True) -> None:
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY.PATH=VALUE",
        help="override a pipeline value, e.g. steps.hht.params.max_imfs=4 or inputs=scans/ "
        "(repeatable; values are YAML)",
    )
    if not running:
        return
    parser.add_argument(
        "--scheduler",
        choices=SCHEDULERS,
        default=None,
        help="Dask scheduler (default: the pipeline's execution.scheduler)",
    )
    parser.add_argument("--workers", type=int, default=None, help="threads, processes or cluster workers")
    parser.add_argument("--address", default=None, help="address of a running dask.distributed scheduler")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="skip inputs whose outputs are done: recorded complete (same size and "
        "checksum) in the output folder's manifest",
    )
    parser.add_argument("--allow-plugins", action="store_true", help="run plugins' operations and python steps")
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace existing local output files that hht3d did not write (kept otherwise)",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="hht3d", description="Hilbert–Huang transform on 3D surfaces")
    parser.add_argument("--version", action="version", version=f"hht3d {__version__}")
    sub = _Subcommands(parser.add_subparsers(dest="command", required=True), logging_options())

    run = sub.add_parser("run", help="validate and run a YAML pipeline")
    run.add_argument("pipeline", help="a pipeline YAML file (see pipelines/)")
    _add_run_options(run)
    run.set_defaults(run=_run)

    validate = sub.add_parser("validate", help="validate a YAML pipeline and print the planned graph")
    validate.add_argument("pipeline")
    _add_run_options(validate, running=False)
    validate.set_defaults(run=_validate)

    ops = sub.add_parser("ops", help="list the pipeline operations, their parameters and defaults")
    ops.add_argument("op", nargs="*", help="only these operations")
    ops.set_defaults(run=_ops)

    schema = sub.add_parser(
        "schema",
        help="print the JSON Schema of pipeline files (for editors; shipped as hht3d/data/pipeline.schema.json)",
    )
    schema.add_argument("--output", default=None, help="write it to this file instead")
    schema.set_defaults(run=_schema)

    info = sub.add_parser(
        "info",
        help="vertices, faces, components, boundary, manifoldness, bounding box; "
        "--backends: the sparse solver that will run and why",
    )
    info.add_argument("file", nargs="?")
    info.add_argument(
        "--backends", action="store_true", help="list the sparse solver backends with their estimated time and memory"
    )
    info.add_argument(
        "--vertices",
        type=int,
        default=50_000,
        help="mesh size of the --backends estimates without FILE (default: 50,000)",
    )
    info.add_argument("--json", action="store_true", help="print JSON")
    info.add_argument("--no-clean", action="store_true", help="describe the file as stored, before cleaning")
    info.set_defaults(run=_info)

    view = sub.add_parser(
        "view",
        help="write the interactive HTML page of a saved result (.npz or .ply) or surface file, and print its path",
    )
    view.add_argument("file", help="a result saved by HHTResult.save or a pipeline, or any mesh or point cloud")
    view.add_argument(
        "--out",
        default=None,
        help="the page to write, a path or URL (default: FILE with the suffix .html; for a URL FILE, STEM.html here)",
    )
    view.add_argument("--field", default=None, help="the field shown first (default: signal)")
    view.add_argument(
        "--max-vertices",
        type=int,
        default=VERTEX_BUDGET,
        help=f"show a decimated copy of larger surfaces (default: {VERTEX_BUDGET:,})",
    )
    view.add_argument("--view", default="front", choices=tuple(VIEWS), help="initial camera (default: front)")
    view.add_argument("--up", default="y", choices=UP_AXES, help="the model's up axis (default: y)")
    view.set_defaults(run=_view)

    demo = sub.add_parser("demo", help="run the demo pipeline: HHT of the shipped model spot (CC0)")
    demo.add_argument("--out", default="out/demo", help="output folder (default: out/demo)")
    _add_run_options(demo)
    demo.set_defaults(run=_demo)
    return parser


class _Subcommands:
    """The subparsers, each made with the logging options."""

    def __init__(self, subparsers: Any, common: argparse.ArgumentParser) -> None:
        self._subparsers, self._common = subparsers, common

    def add_parser(self, name: str, **kwargs: Any) -> argparse.ArgumentParser:
        return self._subparsers.add_parser(name, parents=[self._common], **kwargs)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "info" and args.file is None and not args.backends:
        parser.error("hht3d info needs a FILE, or --backends")
    from .stopping import Stopped, stop_on_signals

    try:
        with stop_on_signals(), showing(log_level(args), info=sys.stdout, force=True):
            return args.run(args)
    except HHT3DError as exc:
        print(f"hht3d: error: {one_line(exc, MAX_MESSAGE)}", file=sys.stderr)
        return 1
    except Stopped as stop:  # before a run started: nothing to clean (a run cleans itself, see _execute)
        print(f"hht3d: stopped by {stop}", file=sys.stderr)
        return stop.exit_code


if __name__ == "__main__":
    sys.exit(main())
