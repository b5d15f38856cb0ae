"""What a pipeline's inputs will cost, said before anything runs.

For every input whose size a header declares (local PLY files), the whole
HHT's peak memory and time on the step's sparse solver come from
:func:`hht3d.linalg.estimate_hht`; ``hht3d validate`` and the start of
``hht3d run`` print them, and a run whose largest input cannot fit in the
memory available is refused with one line before anything is computed.
Inputs of other formats, and URLs, are measured only when loaded (the
solver checks again before its first factorization).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import InputError, PipelineError, one_line
from ..io import read_ply_header
from ..linalg import available_memory, check_memory, estimate_hht
from .plan import Pipeline

if TYPE_CHECKING:
    from hht3d.pipeline.plan import Step


__all__ = ["DECOMPOSING_OPS", "input_sizes", "resource_lines", "check_resources"]

#: Operations that factorize the envelope and Riesz systems the estimator was calibrated on.
DECOMPOSING_OPS = ("emd", "eemd", "hht")


def _decomposing(plan: Pipeline) -> Step | None:
    """The pipeline's first decomposing step (its ``backend`` parameter is the solver), or ``None``."""
    return next((s for s in plan.steps if s.op.name in DECOMPOSING_OPS), None)


def input_sizes(plan: Pipeline) -> dict[str, int]:
    """Vertices of each input whose PLY header declares them."""
    sizes = {}
    for source in plan.inputs:
        if isinstance(source, Path) and source.suffix.lower() == ".ply":
            try:
                sizes[str(source)] = read_ply_header(source).counts.get("vertex", 0)
            except InputError:  # unreadable: the load step reports it with the input's name
                continue
    return sizes


def resource_lines(plan: Pipeline) -> list[str]:
    """One line per sized input: its estimated peak memory and time, and the memory available."""
    step = _decomposing(plan)
    if step is None:
        return []
    available = available_memory()
    lines = []
    for source, vertices in input_sizes(plan).items():
        found = estimate_hht(vertices, step.params.get("backend"))
        if found is not None:
            lines.append(f"estimate: {source}: {found.describe()}")
    if lines and available is not None:
        lines.append(f"estimate: memory available {available / 2**30:.1f} GiB")
    return lines


def check_resources(plan: Pipeline, available: int | None = None) -> None:
    """Refuse, with one line naming the input, a pipeline whose largest sized input cannot fit in memory.

    Raises
    ------
    PipelineError
        The input, its estimate, the memory available and the ways out.
    """
    step, sizes = _decomposing(plan), input_sizes(plan)
    if step is None or not sizes:
        return
    source, vertices = max(sizes.items(), key=lambda item: item[1])
    try:
        check_memory(vertices, step.params.get("backend"), available)
    except InputError as exc:
        raise PipelineError(f"{source}: {one_line(exc)}") from None
