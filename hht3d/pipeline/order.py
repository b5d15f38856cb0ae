"""The order in which a pipeline's steps run: list order, each step moved after the steps it uses."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..errors import PipelineError
from .document import at
from .plan import FILE, Step

__all__ = ["run_order"]


def run_order(steps: list[Step], entries: Sequence[Any]) -> tuple[Step, ...]:
    """Steps in list order, each moved after the steps it uses; a cycle is an error."""
    by_id = {s.id: s for s in steps}
    done: dict[str, bool] = {}  # False while on the current path
    order: list[Step] = []

    def visit(step: Step, path: list[str]) -> None:
        if done.get(step.id) is False:
            cycle = path[path.index(step.id) :] + [step.id]
            entry = entries[steps.index(step)]
            raise PipelineError(
                f"{at(entry, 'from')}: steps {' -> '.join(map(repr, cycle))} form a cycle (each uses the "
                "next); a step can only use results of steps that do not use its own"
            )
        if step.id in done:
            return
        done[step.id] = False
        for ref in step.refs.values():
            if ref != FILE:
                visit(by_id[ref], path + [step.id])
        done[step.id] = True
        order.append(step)

    for step in steps:
        visit(step, [])
    return tuple(order)
