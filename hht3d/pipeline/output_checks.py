"""Validation of a pipeline's ``outputs`` block, and of where its outputs would land.

:func:`read_outputs` checks each ``files`` entry (step, format, options,
placeholders: only ``{stem}``, ``{parent}`` and ``{name}``, without format
specs); :func:`check_plan_outputs` checks the resolved paths of every input
before anything runs: distinct, names the file system takes, inside
a local ``outputs.folder`` after placeholders and symlinks (unless
``outputs.allow_outside: true``), never an input, writable (a URL folder:
a probe object written and removed, :func:`hht3d.io.uploads.check_outputs`).
"""

from __future__ import annotations

import string
from pathlib import Path
from typing import Any

from ..errors import InputError, OutputError, PipelineError, shown
from ..io.folder import check_locations
from ..io.storage import is_url, local_path
from ..io.uploads import check_outputs
from ..output_formats import FORMATS, by_suffix
from ..transform import field_imf
from .document import as_mapping, at, known_keys
from .params import Param, did_you_mean, record_params
from .plan import PLACEHOLDERS, Output, Pipeline, Step

__all__ = ["OUTPUTS_KEYS", "FILE_KEYS", "read_outputs", "check_plan_outputs"]

#: The keys of the outputs block and of an output file.
OUTPUTS_KEYS = ("folder", "summary", "allow_outside", "files")
FILE_KEYS = ("from", "path", "format")


def check_plan_outputs(plan: Pipeline, doc: dict) -> None:
    """Refuse outputs that clash, that no file system takes, that leave the folder, that are inputs,
    or that cannot be written; each message names the output entry, its step and the resolved path.

    Raises
    ------
    PipelineError
    """
    _distinct_paths(plan, doc)
    block: Any = doc.get("outputs")
    entries = block["files"]

    def where(source: Path, path: Path) -> str:
        index = plan.output_paths(source).index(path)
        output = plan.outputs[index]
        return f"{at(entries[index], 'path')}: output {shown(output.path)} of step {shown(output.step)}"

    try:
        check_locations(
            {s: plan.output_paths(s) for s in plan.inputs}, plan.folder, allow_outside=plan.allow_outside, where=where
        )
    except OutputError as exc:
        raise PipelineError(str(exc)) from None
    try:
        check_outputs(plan.written_paths(), plan.storage_options)
    except (OutputError, InputError) as exc:
        raise PipelineError(f"{at(block, 'folder')}: outputs: {exc}") from None


def read_outputs(doc: dict, steps: tuple[Step, ...], source: str) -> tuple[Path | str, Any, Any, Any]:
    """The outputs block: ``(folder, summary, allow_outside, files)``, each file entry checked."""
    block = doc.get("outputs")
    if not isinstance(block, dict) or not block.get("files"):
        raise PipelineError(
            f"{at(doc, 'outputs') if 'outputs' in doc else source}: outputs must be a "
            "mapping with files: a list of {from: STEP, path: PATTERN} entries"
        )
    known_keys(block, OUTPUTS_KEYS, "outputs")
    folder = block.get("folder", "out")
    if not isinstance(folder, str) or not folder:
        raise PipelineError(f"{at(block, 'folder')}: outputs.folder must be a path, got {shown(folder)}")
    folder = local_path(folder)
    summary = Param("summary", "bool", "").check(block.get("summary", True), f"{at(block, 'summary')}: outputs")
    outside = Param("allow_outside", "bool", "").check(
        block.get("allow_outside", False), f"{at(block, 'allow_outside')}: outputs"
    )
    if not isinstance(block["files"], list):
        raise PipelineError(f"{at(block, 'files')}: outputs.files must be a list of {{from, path}} entries")
    by_id = {s.id: s for s in steps}
    last = next(s.id for s in reversed(steps))
    files = tuple(_output(as_mapping(e, at(block, "files"), "an output"), by_id, last) for e in block["files"])
    return folder if is_url(folder) else Path(folder), summary, outside, files


def _output(entry: Any, steps: dict, last: str) -> Output:
    step_id = entry.get("from", last)
    if not isinstance(step_id, str) or step_id not in steps:
        raise PipelineError(
            f"{at(entry, 'from')}: output from unknown step {shown(step_id)}{did_you_mean(step_id, steps)}"
        )
    kind = steps[step_id].kind
    formats = FORMATS.get(kind, {})
    path = entry.get("path")
    if not isinstance(path, str) or not path:
        raise PipelineError(f'{at(entry)}: an output needs a path pattern, e.g. path: "{{stem}}_hht.ply"')
    _placeholders(path, at(entry, "path"))
    name = entry.get("format") or _format_from(path, entry, formats)
    context = f"{at(entry, 'format' if 'format' in entry else 'path')}: output {shown(path)} of step {shown(step_id)}"
    if name not in formats:
        raise PipelineError(
            f"{context}: step {shown(step_id)} makes {kind}, which can be written as "
            f"{', '.join(formats) or 'nothing'}, not {shown(name)}"
        )
    fmt = formats[name]
    if not path.lower().endswith(fmt.suffix):
        raise PipelineError(f"{context}: format {name} writes {fmt.suffix} files; end the path with {fmt.suffix}")
    params = record_params(fmt.options)
    known = [p.name for p in params]
    for key in entry:
        if key not in FILE_KEYS and key not in known:
            raise PipelineError(
                f"{at(entry, key)}: output {shown(path)}: unknown option {shown(key)} for format "
                f"{name}{did_you_mean(key, [*FILE_KEYS, *known])}"
            )
    options = {
        p.name: p.check(entry[p.name], f"{at(entry, p.name)}: output {shown(path)}") if p.name in entry else p.default
        for p in params
    }
    try:
        fmt.options.of(options)
    except InputError as exc:  # what the types cannot say: an unknown field or colour map
        raise PipelineError(f"{context}: {exc}") from None
    _imf_exists(options, steps[step_id], context)
    return Output(step_id, path, fmt, options, tuple(k for k in entry if k in known))


def _imf_exists(options: dict, step: Step, where: str) -> None:
    """Refuse a field ``imf_K`` (or amplitude_K, ...) of an IMF the step cannot make, and a spectrum
    figure of a step that makes no IMF."""
    number, most = field_imf(options.get("field")), step.params.get("max_imfs")
    if number is not None and most is not None and number > most:
        raise PipelineError(
            f"{where}: field {options['field']} needs {number} IMFs, but step {step.id!r} makes "
            f"at most max_imfs: {most}; use K <= {most} or raise max_imfs"
        )
    if options.get("figure") == "spectrum" and most == 0:
        raise PipelineError(
            f"{where}: a spectrum figure needs IMFs, but step {step.id!r} has max_imfs: 0; "
            "raise max_imfs or choose another figure"
        )


def _format_from(path: str, entry: Any, formats: dict) -> str:
    suffix = Path(path).suffix.lower()
    if suffix == ".ply" and ("field" in entry or "cmap" in entry):
        return "colored_ply"
    names = by_suffix()
    if suffix not in names:
        raise PipelineError(
            f"{at(entry, 'path')}: cannot tell the format of {shown(path)}; end it with "
            f"{', '.join(sorted(names))} or give format:"
        )
    return names[suffix]


def _placeholders(path: str, where: str) -> None:
    try:
        parsed = [(f, spec, conversion) for _, f, spec, conversion in string.Formatter().parse(path) if f is not None]
    except ValueError as exc:
        raise PipelineError(f"{where}: bad path pattern {shown(path)}: {exc}") from None
    for f, spec, conversion in parsed:
        if spec or conversion:
            raise PipelineError(
                f"{where}: placeholder {{{shown(f, 20)[1:-1]}...}} in {shown(path)} has a format "
                "spec or conversion; write placeholders plainly: {stem}, {parent}, {name}"
            )
        if f not in PLACEHOLDERS:
            raise PipelineError(
                f"{where}: unknown placeholder {{{f}}} in {shown(path)}"
                f"{did_you_mean(f, PLACEHOLDERS)}"
                f" (use {', '.join('{' + p + '}' for p in PLACEHOLDERS)})"
            )


def _distinct_paths(plan: Pipeline, doc: dict) -> None:
    seen: dict[Path | str, Path | str] = {}
    for source in plan.inputs:
        for path in plan.output_paths(source):
            if path in seen:
                other = seen[path]
                clash = "two outputs" if other == source else f"inputs {other} and {source}"
                raise PipelineError(
                    f"{at(doc, 'outputs')}: {clash} would both write {path}; make the path "
                    "patterns distinct (use {stem} or {parent})"
                )
            seen[path] = source
