"""The validated pipeline: typed, complete, and checked before anything runs.

:func:`hht3d.pipeline.load_pipeline` turns YAML into a :class:`Pipeline`;
every default is filled in, every reference resolved, every input file
found, so the runner (:mod:`hht3d.pipeline.runner`) only compiles it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..dataset.summary import summary_paths
from ..decomposition.display import summary_html
from ..execution import ExecutionOptions
from ..io.storage import join, parent_name, stem
from ..output_formats import Format
from ..redaction import redact
from .params import yaml_text
from .registry import Operation

__all__ = ["FILE", "ExecutionOptions", "Step", "Output", "Pipeline"]

#: Reference of a ``file`` slot: the input file of the item being processed.
FILE = "<input file>"

#: Placeholders of output path patterns.
PLACEHOLDERS = ("stem", "parent", "name")


@dataclass(frozen=True)
class Step:
    """One step: its operation, checked parameters (defaults filled in) and resolved inputs.

    ``refs`` maps each slot of the operation to the id of the step whose
    result it takes (:data:`FILE` for the input file); ``given`` are the
    parameter names the pipeline set explicitly.
    """

    id: str
    op: Operation
    params: dict
    refs: dict
    given: tuple[str, ...] = ()

    @property
    def kind(self) -> str:
        return self.op.output_kind(self.params)


@dataclass(frozen=True)
class Output:
    """One file per input: the result of step ``step`` written as ``format`` to ``path``.

    ``options`` are the format's options with defaults filled in; ``given``
    names those the pipeline set.
    """

    step: str
    path: str
    format: Format
    options: dict = field(default_factory=dict)
    given: tuple[str, ...] = ()

    def resolve(self, folder: Path | str, source: Path | str, name: str) -> Path | str:
        """The file (or URL) for one input: placeholders ``{stem}``, ``{parent}``, ``{name}`` filled in."""
        return join(folder, self.path.format(stem=stem(source), parent=parent_name(source), name=name))


@dataclass(frozen=True)
class Pipeline:
    """A validated pipeline.

    Attributes
    ----------
    name : str
    source : str
        The YAML file it came from (for messages).
    execution : Execution
    inputs : tuple of Path or str
        The input files, resolved (URLs stay strings).
    steps : tuple of Step
        In an order where every step follows the steps it uses.
    outputs : tuple of Output
    folder : Path or str
        Output folder (a path or URL); output paths are relative to it.
    summary : bool
        Write ``summary.json`` and ``summary.csv`` in ``folder``.
    storage_options : dict
        Options of the fsspec back-end of URL inputs and outputs (:mod:`hht3d.io.storage`).
    allow_outside : bool
        Outputs may resolve outside ``folder`` (``outputs.allow_outside``;
        refused by validation otherwise).
    """

    name: str
    source: str
    execution: ExecutionOptions
    inputs: tuple[Path | str, ...]
    steps: tuple[Step, ...]
    outputs: tuple[Output, ...]
    folder: Path | str
    summary: bool = True
    storage_options: dict = field(default_factory=dict)
    allow_outside: bool = False

    def step(self, step_id: str) -> Step:
        return next(s for s in self.steps if s.id == step_id)

    def output_paths(self, source: Path | str) -> list[Path | str]:
        """The files the pipeline writes for one input, in the order of :attr:`outputs`."""
        return [o.resolve(self.folder, source, self.name) for o in self.outputs]

    def written_paths(self) -> list[Path | str]:
        """Every file a run writes: the outputs of every input, then the summary files if any."""
        outputs = [path for source in self.inputs for path in self.output_paths(source)]
        return outputs + (summary_paths(self.folder) if self.summary else [])

    def surface_of(self, step_id: str) -> str:
        """Id of the step whose surface a step's result lives on (itself for a surface)."""
        step = self.step(step_id)
        return step.id if step.kind == "surface" else self.origin_of(step_id)

    def origin_of(self, step_id: str) -> str:
        """Id of the surface a step's result was computed from: the one it lives on, or for a
        surface made from another (``filter_geometry``, ``reconstruct``, ...) that other one;
        a ``load`` step is its own origin."""
        step = self.step(step_id)
        slot = "surface" if "surface" in step.refs else next(iter(step.refs))
        ref = step.refs[slot]
        return step.id if ref == FILE else self.surface_of(ref)

    def __repr__(self) -> str:
        return (
            f"Pipeline({self.name!r}: {_count(len(self.inputs), 'input')}, {_count(len(self.steps), 'step')}, "
            f"{_count(len(self.outputs), 'output')} per input, folder {redact(str(self.folder))!r})"
        )

    def _repr_html_(self) -> str:
        """The plan as a notebook shows it: the inputs, each step with the parameters the pipeline
        set, and each output with the file it makes from the first input."""
        ex = self.execution
        facts = [
            ("source", self.source),
            ("execution", f"scheduler {ex.scheduler}, workers {ex.workers or 'one per core'}, seed {ex.seed}"),
            ("output folder", redact(str(self.folder)) + (" (with summary.json/.csv)" if self.summary else "")),
        ]
        inputs = (["input"], [[redact(str(p))] for p in self.inputs])
        steps = (
            ["step", "operation", "uses", "parameters set", "result"],
            [
                [
                    s.id,
                    s.op.name,
                    ", ".join(f"{slot}={'file' if ref == FILE else ref}" for slot, ref in s.refs.items()),
                    ", ".join(f"{k}={yaml_text(s.params[k])}" for k in s.given) or "defaults",
                    s.kind,
                ]
                for s in self.steps
            ],
        )
        outputs = (
            ["output of", "path", "format", "e.g."],
            [
                [o.step, o.path, o.format.name, redact(str(path))]
                for o, path in zip(self.outputs, self.output_paths(self.inputs[0]))
            ],
        )
        return summary_html(f"Pipeline: {self.name}", facts, [inputs, steps, outputs])

    def describe(self) -> str:
        """The planned graph as text (``hht3d validate``)."""
        ex = self.execution
        where = f" at {ex.address}" if ex.address else ""
        files = f"{len(self.inputs)} input file{'' if len(self.inputs) == 1 else 's'}"
        header = f"pipeline {self.name!r} ({self.source}): {files}, {len(self.steps)} steps"
        lines = [
            f"{header}, {len(self.outputs)} outputs per input",
            (
                f"execution: scheduler {ex.scheduler}{where}, workers {ex.workers or 'one per core'}, "
                f"progress {yaml_text(ex.progress)}, seed {ex.seed}"
            ),
            "inputs:",
        ]
        lines += [f"  {p}" for p in self.inputs]
        lines.append("steps:")
        width = max(len(s.id) for s in self.steps)
        for s in self.steps:
            uses = ", ".join(f"{slot}={'file' if ref == FILE else ref}" for slot, ref in s.refs.items())
            lines.append(f"  {s.id:<{width}}  {s.op.name}({uses}) -> {s.kind}")
            if s.given:
                lines.append(f"  {'':<{width}}    " + ", ".join(f"{k}={yaml_text(s.params[k])}" for k in s.given))
        lines.append(f"outputs (folder {self.folder}" + (", with summary.json/.csv):" if self.summary else "):"))
        example = self.inputs[0]
        for o, path in zip(self.outputs, self.output_paths(example)):
            options = "".join(f", {k}={yaml_text(o.options[k])}" for k in o.given)
            lines.append(f"  {o.step} -> {o.path} ({o.format.name}{options}), e.g. {path}")
        return "\n".join(lines)


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"
