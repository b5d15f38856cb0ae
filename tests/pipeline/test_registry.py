"""The operations (hht3d.pipeline.registry): a new one is one core function and one entry; every numeric parameter
has an upper bound."""

import dataclasses
import textwrap

import numpy as np
import pytest

from hht3d.geometry.signals import mean_curvature
from hht3d.io import load
from hht3d.pipeline import OPERATIONS, parse_pipeline, run_pipeline
from hht3d.pipeline.validation import EXECUTION
from hht3d.records import Record, option


def _scaled(surface, signal, *, factor: float = 2.0):
    """A made-up core function: the signal times a factor."""
    return factor * np.asarray(signal)


@dataclasses.dataclass(frozen=True)
class _ScaledOptions(Record):
    factor: float = option(2.0, "the factor", minimum=0)


def test_a_new_operation_is_one_core_function_and_one_entry(monkeypatch, tmp_path, mesh_file):
    from hht3d.pipeline import Operation, Slot
    from hht3d.pipeline.params import record_params

    monkeypatch.setitem(
        OPERATIONS,
        "scaled",
        Operation(
            "scaled",
            "the signal times a factor",
            (Slot("surface", ("surface",)), Slot("signal", ("signal",))),
            "signal",
            record_params(_ScaledOptions),
            func=_scaled,
        ),
    )
    text = textwrap.dedent(f"""\
        version: 1
        execution: {{scheduler: synchronous, progress: false}}
        inputs: {mesh_file}
        steps:
          - {{op: signal, params: {{kind: mean_curvature}}}}
          - {{id: tripled, op: scaled, params: {{factor: 3}}}}
        outputs:
          folder: {tmp_path / "out"}
          files: [{{from: tripled, path: tripled.npz}}]
        """)
    plan = parse_pipeline(text)
    assert plan.step("tripled").params == {"factor": 3.0}
    (row,) = run_pipeline(plan)
    assert row.status == "ok", row.error
    np.testing.assert_array_equal(
        np.load(tmp_path / "out" / "tripled.npz")["signal"], 3.0 * mean_curvature(load(mesh_file))
    )
    with pytest.raises(Exception, match="parameter factor must be a number >= 0"):
        parse_pipeline(text.replace("factor: 3", "factor: -1"))


#: Numeric parameters in model units, which scale with the model: only required to be finite.
MODEL_UNITS = {"merge_radius", "time"}


def test_every_numeric_parameter_has_an_upper_bound():
    """Issue 15: a typo such as riesz_tasks: 100000 must be refused, so every new parameter needs a maximum."""
    params = [p for op in OPERATIONS.values() for p in op.params] + list(EXECUTION)
    unbounded = {p.name for p in params if p.kind in ("int", "float") and p.maximum is None} - MODEL_UNITS
    assert not unbounded, f"give these parameters a maximum (hht3d/pipeline/registry.py): {sorted(unbounded)}"
