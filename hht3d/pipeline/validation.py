"""Reading and validating pipeline YAML (schema version 1) into a :class:`~.plan.Pipeline`.

::

    version: 1                      # required
    name: demo                      # optional; default the file's stem
    execution:                      # optional
      scheduler: threads            # synchronous | threads | processes | distributed
      workers: 2                    # default one per core
      address: tcp://host:8786      # an existing dask.distributed scheduler
      progress: true
      seed: 0                       # default seed of every randomised step (EEMD)
    inputs: scans/                  # a file, a folder, a glob, a list of them,
                                    # or {builtin: spot} (a model shipped in the package);
                                    # fsspec URLs too: s3://bucket/scans/*.ply
    storage_options:                # optional: of the fsspec back-end of URLs (never credentials:
      client_kwargs: {endpoint_url: https://s3.example.org}  # those come from the environment)
    steps:                          # run per input file
      - id: curvature               # optional; default the op name
        op: signal                  # one of `hht3d ops` (built-in, or a plugin's: plugins.py)
        params: {kind: mean_curvature}
      - id: hht
        op: hht
        from: {signal: curvature}   # optional: a step id, or {slot: step id}
        params: {max_imfs: 6}
    outputs:
      folder: out/demo              # default "out"; or a URL: s3://bucket/results
      summary: true                 # summary.json / summary.csv (default true)
      allow_outside: false          # let outputs resolve outside folder (default false)
      files:
        - {from: hht, path: "{stem}_hht.ply"}
        - {from: hht, path: "{stem}_frequency_1.ply", format: colored_ply, field: frequency_1}
        # from: default the last step to run; format: default from the suffix
        # (.ply with field or cmap: colored_ply); path placeholders {stem}, {parent}, {name}
        # (no format specs); every output must resolve inside folder and never be an input

Steps without ``load`` get an implicit first step ``{id: load, op: load}``
(``--set steps.load.params.laplacian=robust`` reaches it).  A slot not named in
``from`` takes the result of the nearest earlier step of a kind it accepts, so a
linear chain needs no references.  Relative paths are relative to the working
directory.  Every error is a :class:`~hht3d.errors.PipelineError` naming the
file and line (or the ``--set`` override) and what to change.

Validation checks everything cheap to know before computing, and builds no
task graph: every parameter against its record's range (``hht3d ops``),
input extensions, ``eigenpairs`` against PLY vertex counts, output fields
against ``max_imfs``, and that every output can be written.  Reading the YAML
(floats as in YAML 1.2, alias bombs refused, ``--set``) is
:mod:`hht3d.pipeline.document`'s; this module checks what it says.
"""

from __future__ import annotations

import string
from pathlib import Path
from typing import Any, Iterable, Sequence, cast

from ..errors import InputError, PipelineError, shown
from ..io import data_path, read_ply_header
from ..io.storage import is_url, resolve_locations
from .document import YAMLMapping, add_implicit_load, apply_overrides, as_mapping, at, known_keys, read_yaml
from .order import run_order
from .output_checks import FILE_KEYS, OUTPUTS_KEYS, check_plan_outputs, read_outputs
from .params import did_you_mean, record_params
from .plan import FILE, ExecutionOptions, Pipeline, Step
from .plugins import operation, operations
from .registry import RENAMED
from .storage_options import storage_options

__all__ = [
    "VERSION",
    "EXECUTION",
    "TOP_KEYS",
    "STEP_KEYS",
    "OUTPUTS_KEYS",
    "FILE_KEYS",
    "load_pipeline",
    "parse_pipeline",
    "builtin_models",
    "Validator",
]

#: The schema version this package reads.
VERSION = 1

#: The keys of a pipeline and of a step (those of the outputs block: :mod:`.output_checks`).
TOP_KEYS = ("version", "name", "execution", "storage_options", "inputs", "steps", "outputs")
STEP_KEYS = ("id", "op", "from", "params")
#: Parameters of the ``execution`` block (also the checks of the CLI's --scheduler and --workers).
EXECUTION = record_params(ExecutionOptions)
_ID_CHARS = set(string.ascii_letters + string.digits + "_-")
#: The longest step id.
MAX_ID = 64


# -- validation -----------------------------------------------------------------------------------
def load_pipeline(path: Path | str, overrides: Iterable[str] = ()) -> Pipeline:
    """Read, override and validate a pipeline file.

    Parameters
    ----------
    path : str or Path
        A YAML file.
    overrides : sequence of str
        ``key.path=value`` assignments (the CLI's ``--set``).

    Raises
    ------
    PipelineError
        The first problem found, with its file and line.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise PipelineError(f"{path}: cannot read the pipeline ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise PipelineError(
            f"{path}: cannot read the pipeline: byte {exc.start} is not UTF-8 text; save the file as UTF-8"
        ) from None
    return parse_pipeline(text, source=str(path), overrides=overrides)


def parse_pipeline(text: str, *, source: str = "<pipeline>", overrides: Iterable[str] = ()) -> Pipeline:
    """Validate pipeline YAML given as text; see :func:`load_pipeline`."""
    document = read_yaml(text, source)
    if not isinstance(document, dict):
        raise PipelineError(
            f"{source}: a pipeline is a YAML mapping with version, inputs, steps and "
            f"outputs; got {type(document).__name__ if document is not None else 'an empty file'}"
        )
    add_implicit_load(document)
    apply_overrides(document, overrides)
    return Validator(source).pipeline(document)


def builtin_models() -> dict[str, Path]:
    """The models shipped in the package, by name (``spot``, ...)."""
    folder = data_path("")
    return {p.stem: p for p in folder.iterdir() if p.suffix == ".ply"}


class Validator:
    """Checks a read pipeline document and builds the typed :class:`~hht3d.pipeline.plan.Pipeline`.

    One validator reads one document (the mappings of
    :func:`~hht3d.pipeline.document.read_yaml`, overrides applied), top
    down: version, name, execution, inputs, steps, outputs.  Every method
    raises :class:`~hht3d.errors.PipelineError` at the first problem, with
    the ``file:line`` of the offending key (:func:`~hht3d.pipeline.document.at`),
    what was expected, what was found and, for unknown names, the closest
    known one ("did you mean").  Checks that need the inputs (vertex counts
    from PLY headers, for ``eigenpairs``) read them once and keep them.

    Parameters
    ----------
    source : str
        The file (or ``<pipeline>``) named in messages about the document as a whole.

    Examples
    --------
    >>> from hht3d.pipeline.document import add_implicit_load, read_yaml
    >>> text = ("version: 1\\n"
    ...         "inputs: {builtin: spot}\\n"
    ...         "steps: [{op: signal, params: {kind: mean_curvatur}}]\\n"
    ...         "outputs: {files: [{path: curvature.npz}]}\\n")
    >>> document = read_yaml(text, "demo.yaml")
    >>> add_implicit_load(document)
    >>> Validator("demo.yaml").pipeline(document)
    Traceback (most recent call last):
    hht3d.errors.PipelineError: demo.yaml:3: step 'signal' (op signal): parameter kind must be one of
    ...; got 'mean_curvatur' (a string); did you mean 'mean_curvature'?
    >>> document["steps"][1]["params"]["kind"] = "mean_curvature"
    >>> [step.id for step in Validator("demo.yaml").pipeline(document).steps]
    ['load', 'signal']
    """

    def __init__(self, source: str):
        self.source = source
        self.inputs: tuple[Path | str, ...] = ()
        self._vertex_counts: dict[Path | str, int] | None = None

    def pipeline(self, doc: dict) -> Pipeline:
        known_keys(doc, TOP_KEYS, "the pipeline")
        self._version(doc)
        name = doc.get("name", Path(self.source).stem)
        if not isinstance(name, str) or not name:
            raise PipelineError(f"{at(doc, 'name')}: name must be a non-empty string, got {shown(name)}")
        execution = self._execution(doc.get("execution") or YAMLMapping(at(doc, "execution")))
        self.storage_options = storage_options(doc)
        inputs = self.inputs = self._inputs(doc)
        steps = self._steps(doc, execution)
        folder, summary, allow_outside, outputs = read_outputs(doc, steps, self.source)
        plan = Pipeline(
            name=name,
            source=self.source,
            execution=execution,
            inputs=inputs,
            steps=steps,
            outputs=outputs,
            folder=folder,
            summary=summary,
            storage_options=self.storage_options,
            allow_outside=allow_outside,
        )
        check_plan_outputs(plan, doc)
        return plan

    def _version(self, doc: dict) -> None:
        if "version" not in doc:
            raise PipelineError(f"{self.source}: missing 'version: {VERSION}' (the schema version) at the top")
        if doc["version"] != VERSION or isinstance(doc["version"], bool):
            raise PipelineError(
                f"{at(doc, 'version')}: unsupported pipeline version {shown(doc['version'])}; "
                f"this hht3d reads version {VERSION}"
            )

    def _execution(self, block: Any) -> ExecutionOptions:
        block = as_mapping(block, at(block), "execution")
        known_keys(block, [p.name for p in EXECUTION], "execution")
        values: dict[str, Any] = {
            p.name: p.check(block[p.name], f"{at(block, p.name)}: execution") if p.name in block else p.default
            for p in EXECUTION
        }
        return ExecutionOptions(**values)

    def _inputs(self, doc: dict) -> tuple[Path | str, ...]:
        if "inputs" not in doc or doc["inputs"] in (None, [], ""):
            raise PipelineError(
                f"{self.source}: missing inputs: give a file, a folder, a glob, a list of them, or {{builtin: spot}}"
            )
        spec, where = doc["inputs"], at(doc, "inputs")
        if isinstance(spec, dict):
            known_keys(spec, ["builtin"], "inputs")
            models = builtin_models()
            name = spec.get("builtin")
            if name not in models:
                raise PipelineError(
                    f"{at(spec, 'builtin')}: unknown builtin model {shown(name)}{did_you_mean(cast(str, name), models)}"
                )
            return (models[name],)
        items = spec if isinstance(spec, list) else [spec]
        if not all(isinstance(item, str) and item for item in items):
            raise PipelineError(
                f"{where}: inputs must be a path, a glob, a folder or a list of them, got {shown(spec)}"
            )
        try:
            return tuple(resolve_locations(items, self.storage_options))
        except InputError as exc:
            raise PipelineError(f"{where}: inputs: {exc}") from None

    # -- steps ----------------------------------------------------------------------------------
    def _steps(self, doc: dict, execution: ExecutionOptions) -> tuple[Step, ...]:
        raw = doc.get("steps")
        if not isinstance(raw, list) or not raw:
            raise PipelineError(
                f"{at(doc, 'steps') if 'steps' in doc else self.source}: steps must be a "
                "non-empty list of {id, op, params} entries"
            )
        entries = [as_mapping(e, at(doc, "steps"), f"step {i + 1}") for i, e in enumerate(raw)]
        parsed = [self._step(entry, execution) for entry in entries]
        ids = [p[0] for p in parsed]
        for i, step_id in enumerate(ids):
            if step_id in ids[:i]:
                raise PipelineError(
                    f"{at(entries[i], 'id')}: two steps have the id {shown(step_id)}; give each step a distinct id"
                )
        steps = [
            Step(step_id, op, params, self._refs(entries, parsed, i), given)
            for i, (step_id, op, params, given) in enumerate(parsed)
        ]
        return run_order(steps, entries)

    def _step(self, entry: Any, execution: ExecutionOptions) -> tuple[str, Any, dict, tuple]:
        known_keys(entry, STEP_KEYS, "a step")
        where = at(entry, "op")
        if "op" not in entry:
            raise PipelineError(f"{at(entry)}: a step needs an op (`hht3d ops` lists them)")
        op = operation(entry["op"], where)
        step_id = entry.get("id", op.name)
        if not isinstance(step_id, str) or not 0 < len(step_id) <= MAX_ID or not set(step_id) <= _ID_CHARS:
            raise PipelineError(
                f"{at(entry, 'id')}: step id must be 1 to {MAX_ID} letters, digits, '_' or '-', got {shown(step_id)}"
            )
        context = f"step {shown(step_id)} (op {op.name})"
        raw = as_mapping(entry.get("params") or YAMLMapping(at(entry)), at(entry, "params"), f"{context} params")
        for key in raw:
            if op.param(key) is None:
                known = [p.name for p in op.params]
                hint = (
                    f"; did you mean {RENAMED[key]}? ({key} was renamed {RENAMED[key]} in 0.2.0)"
                    if RENAMED.get(key) in known
                    else did_you_mean(key, known)
                )
                raise PipelineError(
                    f"{at(raw, key)}: {context}: unknown parameter {shown(key)}{hint} "
                    f"(`hht3d ops {op.name}` lists them)"
                )
        params = {}
        for p in op.params:
            if p.name in raw:
                params[p.name] = p.check(raw[p.name], f"{at(raw, p.name)}: {context}")
            elif p.required:
                raise PipelineError(f"{at(entry)}: {context}: missing required parameter {p.name} ({p.describe()})")
            else:
                params[p.name] = p.default
        if "seed" in params and params["seed"] is None:
            params["seed"] = execution.seed
        if op.check is not None:
            op.check(params, f"{at(entry)}: {context}")
        need = op.fewest_vertices(params)
        if need is not None:
            self._enough_vertices(*need, params, f"{at(raw, need[0]) if need[0] in raw else at(entry)}: {context}")
        return step_id, op, params, tuple(raw)

    def _enough_vertices(self, name: str, fewest: int, params: dict, where: str) -> None:
        """Refuse a parameter that needs more vertices than a PLY input declares in its header."""
        for source, count in self._counts().items():
            if count < fewest:
                raise PipelineError(
                    f"{where}: {name}: {params[name]} needs at least {fewest} vertices, but "
                    f"{source} has {count}; lower {name} below {count}"
                )

    def _counts(self) -> dict[Path | str, int]:
        """Vertex counts of the PLY inputs, from their headers (others, and unreadable ones, are left out:
        the load step reports those)."""
        if self._vertex_counts is None:
            self._vertex_counts = {}
            for source in self.inputs:
                if not is_url(source) and cast(Path, source).suffix.lower() == ".ply":  # URLs: the load step reports
                    try:
                        self._vertex_counts[source] = read_ply_header(source).counts.get("vertex", 0)
                    except InputError:
                        continue
        return self._vertex_counts

    def _refs(self, entries: Sequence[Any], parsed: Sequence[Any], i: int) -> dict:
        entry, (step_id, op, _, _) = entries[i], parsed[i]
        kinds = {p[0]: p[1].output_kind(p[2]) for p in parsed}
        context = f"{at(entry, 'from')}: step {shown(step_id)} (op {op.name})"
        explicit = self._explicit_refs(entry, op, kinds, context)
        refs = {}
        for slot in op.slots:
            if slot.kinds == ("file",):
                refs[slot.name] = FILE
            elif slot.name in explicit:
                refs[slot.name] = explicit[slot.name]
            else:
                earlier = [p[0] for p in parsed[:i] if kinds[p[0]] in slot.kinds]
                if not earlier:
                    makers = sorted(o.name for o in operations().values() if o.output in slot.kinds and not o.kind_of)
                    raise PipelineError(
                        f"{at(entry)}: step {shown(step_id)} (op {op.name}) needs {' or '.join(slot.kinds)} input "
                        f"{shown(slot.name)}, and no earlier step makes one; add a step with op "
                        f"{' or '.join(makers)} before it, or name one with from: {{{slot.name}: STEP_ID}}"
                    )
                refs[slot.name] = earlier[-1]
        return refs

    def _explicit_refs(self, entry: Any, op: Any, kinds: dict, context: str) -> dict:
        given = entry.get("from")
        if given is None:
            return {}
        slots = {s.name: s for s in op.slots if s.kinds != ("file",)}
        if isinstance(given, str):
            self._known_step(given, kinds, context, "from")
            matching = [s for s in slots.values() if kinds[given] in s.kinds]
            if not matching:
                raise PipelineError(
                    f"{context}: from: {shown(given)} makes {kinds[given]}, which op {op.name} does "
                    f"not take; it takes {self._takes(slots)}"
                )
            return {matching[0].name: given}
        if not isinstance(given, dict):
            raise PipelineError(f"{context}: from must be a step id or a mapping {{slot: step id}}, got {shown(given)}")
        refs = {}
        for slot, ref in given.items():
            if slot not in slots:
                raise PipelineError(
                    f"{context}: op {op.name} has no input {shown(slot)}"
                    f"{did_you_mean(slot, slots, listing=False)} (it takes {self._takes(slots)})"
                )
            self._known_step(ref, kinds, context, f"from.{slot}")
            if kinds[ref] not in slots[slot].kinds:
                raise PipelineError(
                    f"{context}: from.{slot}: step {shown(ref)} makes {kinds[ref]}, but {slot} "
                    f"needs {' or '.join(slots[slot].kinds)}"
                )
            refs[slot] = ref
        return refs

    @staticmethod
    def _takes(slots: dict) -> str:
        return ", ".join(f"{name} ({' or '.join(s.kinds)})" for name, s in slots.items()) or "no step results"

    @staticmethod
    def _known_step(ref: Any, kinds: dict, context: str, what: str) -> None:
        if not isinstance(ref, str) or ref not in kinds:
            raise PipelineError(f"{context}: {what} refers to unknown step {shown(ref)}{did_you_mean(ref, kinds)}")
