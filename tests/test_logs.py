"""hht3d's messages through the ``hht3d`` loggers (:mod:`hht3d.logs`) and the CLI's levels.

Oracles: the standard library's own logging machinery (a handler the test attaches, as an
application would) and the version string of ``hht3d/version.py``.
"""

from __future__ import annotations

import io
import logging
import time

import pytest
from dask import delayed

from hht3d import version
from hht3d.cli import main
from hht3d.execution import compute
from hht3d.logs import get_logger

SECRET = "wJalrXUtnFEMIK7MDENGbPxRfiCYzEXAMPLEKEY"


@pytest.fixture
def captured():
    """A handler of the application's on the ``hht3d`` logger."""
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    top = logging.getLogger("hht3d")
    top.addHandler(handler)
    level = top.level
    top.setLevel(logging.DEBUG)
    yield stream
    top.removeHandler(handler)
    top.setLevel(level)


def test_no_handler_sees_a_signed_url_or_a_password(captured):
    for name in ("hht3d", "hht3d.progress", "hht3d.execution", "hht3d.cli"):
        get_logger(name).warning(
            "reading %s and %s", f"https://b.example/x.ply?X-Amz-Signature={SECRET}", f"s3://user:{SECRET}@bucket/x.ply"
        )
    text = captured.getvalue()
    assert text.count("***") == 8 and SECRET.lower() not in text.lower()


def test_progress_goes_to_the_applications_handler(captured, capfd, monkeypatch):
    """With a handler of the application's on hht3d's loggers, the plain progress lines are its
    records, not extra lines on stderr."""
    monkeypatch.setattr("hht3d.execution.progress.PROGRESS_INTERVAL", 0.05)
    compute(*[delayed(time.sleep, pure=False)(0.02) for _ in range(10)], scheduler="synchronous", progress=True)
    assert "tasks done" in captured.getvalue()
    assert "tasks done" not in capfd.readouterr().err


def test_version_is_the_packages(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0 and capsys.readouterr().out.strip() == f"hht3d {version.__version__}"


@pytest.mark.parametrize(
    "flags, shown", [((), True), (("-q",), False), (("--log-level", "warning"), False), (("-v",), True)]
)
def test_levels_of_the_cli(flags, shown, tmp_path, capfd):
    """The memory and time estimates are info messages on stdout, beside the results: shown by
    default and with -v, not with -q or --log-level warning; stderr stays empty."""
    assert (
        main(
            [
                "demo",
                "--out",
                str(tmp_path / "out"),
                "--scheduler",
                "synchronous",
                "--set",
                "steps.hht.params.max_imfs=1",
                *flags,
            ]
        )
        == 0
    )
    out, err = capfd.readouterr()
    assert ("hht3d: estimate:" in out) == shown
    assert "spot.ply: ok" in out and err == ""


def test_log_level_is_checked(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["ops", "--log-level", "loud"])
    assert stop.value.code == 2 and "invalid choice: 'loud'" in capsys.readouterr().err


@pytest.mark.slow
def test_a_distributed_run_leaves_the_distributed_loggers_as_they_were():
    """``distributed.client`` is quieted only while hht3d waits on a cluster."""
    client_logger = logging.getLogger("distributed.client")
    client_logger.setLevel(logging.INFO)
    try:
        (value,) = compute(delayed(sum)([1, 2]), scheduler="distributed", workers=1, progress=False)
        assert value == 3
        assert client_logger.level == logging.INFO
    finally:
        client_logger.setLevel(logging.NOTSET)
