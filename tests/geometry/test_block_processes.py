"""The blocks of a large surface's robust Laplacian built in child processes (hht3d.geometry.block_processes).

Oracle: the same blocks built in this process, which tests/geometry/test_blocks.py checks against
``robust_laplacian`` on the whole surface.  Each block is the same computation on the same input in
either place, and the rows are assembled in block order, so the two Laplacians are equal to the bit.
"""

import numpy as np
import psutil
import pytest

import hht3d
from helpers import block_calls
from helpers.models import shared_model_path
from hht3d.errors import InputError
from hht3d.geometry.block_processes import PROCESSES_ENV, mapped, process_count
from hht3d.geometry.normals import estimate_point_normals
from hht3d.geometry.operators import point_cloud_operators


def _is_block_process(child):
    try:  # other tests leave children of their own (a resource tracker, a cluster)
        return child.status() != psutil.STATUS_ZOMBIE and any("block_processes" in part for part in child.cmdline())
    except psutil.Error:  # ended meanwhile
        return False


def _no_children_left():
    assert not [child for child in psutil.Process().children(recursive=True) if _is_block_process(child)]


def test_blocks_built_in_two_processes_are_those_built_here(monkeypatch):
    points = hht3d.load(shared_model_path("rocker_arm.ply")).vertices
    monkeypatch.setattr("hht3d.geometry.operators.CLOUD_BLOCK", 2_500)
    monkeypatch.setenv(PROCESSES_ENV, "1")
    here, here_mass = point_cloud_operators(points)
    monkeypatch.setenv(PROCESSES_ENV, "2")
    there, there_mass = point_cloud_operators(points)
    assert (here != there).nnz == 0 and np.array_equal(here.indices, there.indices)
    np.testing.assert_array_equal(here_mass, there_mass)
    _no_children_left()


def test_a_cloud_built_in_processes_has_its_normals_estimated_meanwhile_the_same(monkeypatch):
    """A cloud whose Laplacian children build has its normals once the Laplacian is there, those it would
    estimate when asked (the same function on the same points, in a thread)."""
    points = hht3d.load(shared_model_path("rocker_arm.ply")).vertices
    monkeypatch.setattr("hht3d.geometry.operators.CLOUD_BLOCK", 2_500)
    monkeypatch.setenv(PROCESSES_ENV, "2")
    cloud = hht3d.Surface(points)
    assert cloud.stiffness.shape == (len(points), len(points))
    assert "normals" in cloud.cache
    np.testing.assert_array_equal(cloud.normals, estimate_point_normals(cloud.vertices))
    _no_children_left()


def test_normals_that_cannot_be_estimated_fail_when_asked_for_not_with_the_laplacian(monkeypatch):
    def refused(points, k=30):
        raise InputError("cannot estimate the point normals (a test)")

    points = hht3d.load(shared_model_path("rocker_arm.ply")).vertices
    monkeypatch.setattr("hht3d.geometry.operators.CLOUD_BLOCK", 2_500)
    monkeypatch.setattr("hht3d.geometry.operators.estimate_point_normals", refused)
    monkeypatch.setattr("hht3d.geometry.surface.estimate_point_normals", refused)
    monkeypatch.setenv(PROCESSES_ENV, "2")
    cloud = hht3d.Surface(points)
    assert cloud.stiffness.nnz > 0
    with pytest.raises(InputError, match="cannot estimate the point normals"):
        cloud.normals  # noqa: B018 (the property raises)
    _no_children_left()


def test_calls_come_back_in_order_from_every_child_and_native_output_does_not_corrupt_them():
    values = [np.arange(k, dtype=float) for k in range(1, 40)]
    for got, sent in zip(mapped(block_calls.doubled, ((v,) for v in values), 3), values, strict=True):
        np.testing.assert_array_equal(got, 2 * sent)
    assert len(set(mapped(block_calls.process_id, ((k,) for k in range(12)), 3))) == 3
    _no_children_left()


def test_an_exception_in_a_child_is_raised_here_and_the_children_end():
    with pytest.raises(ValueError, match="block of 5 refused"):
        list(mapped(block_calls.refused, [(np.zeros(5),)] * 4, 2))
    _no_children_left()


def test_a_child_that_ends_without_an_answer_is_reported_with_its_exit_code():
    with pytest.raises(RuntimeError, match="ended with code 3"):
        list(mapped(block_calls.ended, [(np.zeros(5),)] * 4, 2))
    _no_children_left()


@pytest.mark.parametrize("value", ["0", "two", "-1"])
def test_a_process_count_that_is_not_a_positive_integer_is_refused(monkeypatch, value):
    monkeypatch.setenv(PROCESSES_ENV, value)
    with pytest.raises(InputError, match=PROCESSES_ENV):
        process_count()


def test_without_the_setting_blocks_use_the_cores_this_process_may_use(monkeypatch):
    monkeypatch.delenv(PROCESSES_ENV, raising=False)
    assert 1 <= process_count() <= (psutil.cpu_count() or 1)
    monkeypatch.delattr("os.sched_getaffinity", raising=False)  # Windows and macOS lack it
    monkeypatch.setattr("os.cpu_count", lambda: 3)
    assert process_count() == 3
