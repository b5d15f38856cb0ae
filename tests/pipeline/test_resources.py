"""What a pipeline's inputs cost (hht3d.pipeline.resources): announced by validate, refused when it cannot fit."""

import pytest

from hht3d.cli import main
from hht3d.pipeline import load_pipeline


def test_inputs_cost_is_announced_and_a_run_that_cannot_fit_is_refused(capsys):
    """validate prints each sized input's estimated peak and time (hht3d.linalg.estimate_hht, the
    plain-install issue's model); with less memory than the estimate, one line refuses before any work."""
    from hht3d import PipelineError, data_path
    from hht3d.linalg import estimate_hht
    from hht3d.pipeline.resources import check_resources, resource_lines

    plan = load_pipeline(data_path("demo.yaml"))
    expected = estimate_hht(2930).describe()
    assert any("spot.ply" in line and expected in line for line in resource_lines(plan))
    with pytest.raises(PipelineError, match=r"spot\.ply: .*needs .* but only .*hht3d\[fast\]"):
        check_resources(plan, available=1)
    assert main(["validate", str(data_path("demo.yaml"))]) == 0
    assert expected in capsys.readouterr().out
