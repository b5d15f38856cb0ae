"""Every code block of the README and of the documentation's Markdown pages runs as written, or names the
test that runs its equivalent.

The Python, YAML and command-line blocks run in a scratch folder holding what they name:
``model.ply`` (the shipped spot), ``scans/`` (spot and the shipped sphere) and ``out/``.  Blocks
that need a cluster, a bucket or a scheduler we do not have here (SLURM, Kubernetes, a lab's S3)
are *mirrored*: the entry names the test that makes the same call against local stand-ins, and
this file checks that the test exists.  A new block without an entry fails
``test_every_block_is_run_or_mirrored``.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

from helpers.models import shipped_model_path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: The pages whose blocks are run: the README and the documentation's Markdown (not the built site, nor
#: the benchmark pages the build writes into docs/benchmarks/ from benchmarks/results/).
GENERATED = {"_build", "benchmarks"}
PAGES = [README, *sorted(p for p in (ROOT / "docs").rglob("*.md") if not GENERATED & set(p.relative_to(ROOT).parts))]
TIMEOUT = 600


def blocks() -> dict[tuple[str, str, int], tuple[str, str]]:
    """``(page, section, k) -> (language, code)`` for the k-th fenced block under each ``#`` or ``##``
    heading of each page (``page`` relative to the repository)."""
    found, counts = {}, {}
    for path in PAGES:
        page, section = str(path.relative_to(ROOT)), ""
        for match in re.finditer(r"^##? ([^\n]+)$|^```(\w*)\n(.*?)^```$", path.read_text(), re.M | re.S):
            if match.group(1):
                section = match.group(1).strip()
                continue
            k = counts.get((page, section), 0)
            counts[(page, section)] = k + 1
            found[(page, section, k)] = (match.group(2), match.group(3))
    return found


@dataclass(frozen=True)
class Mirror:
    """A block run elsewhere: ``test`` is ``path::name`` of the test doing the same thing here."""

    test: str
    why: str


RUN = "run here"
MIRRORED = {
    ("docs/getting_started.md", "Install", 0): Mirror(
        ".ci/wheel::-m pip install --quiet --no-deps", "pip installs the built wheel in a fresh environment"
    ),
    ("README.md", "Two commands", 0): Mirror(
        '.ci/wheel::bin/hht3d" demo', "command 1 runs in CI from the built wheel; command 2 is .ci/run"
    ),
    ("docs/guide/clusters.md", "Running on a cluster", 0): Mirror(
        "tests/io/test_storage.py::remote_run",
        "SLURM and the lab bucket: run_dataset with address=, s3:// and "
        "storage_options on a two-worker scheduler and moto",
    ),
    ("docs/guide/clusters.md", "Running on a cluster", 2): Mirror(
        "tests/io/test_storage.py::test_a_yaml_pipeline_from_s3_to_s3_equals_the_local_run",
        "kubectl: hht3d run --address with s3:// inputs and outputs",
    ),
    ("docs/guide/clusters.md", "Running on a cluster", 3): Mirror(
        "tests/io/test_storage.py::PIPELINE", "a lab's scheduler and S3 endpoint: the same pipeline shape on moto"
    ),
    ("docs/guide/formats.md", "LAS and LAZ (airborne and mobile LiDAR)", 0): Mirror(
        ".ci/setup::lidar", "CI installs the lidar extra with the package"
    ),
    ("docs/guide/formats.md", "LAS and LAZ (airborne and mobile LiDAR)", 1): Mirror(
        "tests/io/test_las.py::test_a_pipeline_filters_classes_reads_intensity_and_writes_imfs_as_extra_bytes",
        "the same steps and output on a LAZ scan written by laspy",
    ),
    ("docs/guide/formats.md", "VTK and the meshio formats (ParaView, PyVista, simulation tools)", 0): Mirror(
        ".ci/setup::meshio", "CI installs the meshio extra with the package"
    ),
    ("docs/guide/pipelines.md", "Operations from other packages", 0): Mirror(
        "tests/pipeline/test_plugins.py::ENTRY_POINTS",
        "the same entry points, in the dist-info of a test distribution on sys.path",
    ),
    ("docs/guide/pipelines.md", "A python step", 0): Mirror(
        "tests/pipeline/test_python_step.py::test_a_python_step_is_refused_without_opt_in_then_makes_a_signal_and_a_surface",
        "python steps from an hht step, on functions of a module written to tmp_path and put on sys.path",
    ),
    ("docs/guide/pipelines.md", "A python step", 1): Mirror(
        "tests/pipeline/test_python_step.py::MODULE", "functions of the same shape, taking an HHTResult"
    ),
    ("docs/guide/formats.md", "E57 (terrestrial scanners)", 0): Mirror(
        ".ci/setup::e57", "CI installs the e57 extra with the package"
    ),
    ("README.md", "Development", 0): Mirror(
        ".ci/run::python3 -m pytest -q",
        "the tests are CI's command; the benchmark "
        "commands are listed in benchmarks/README.md and not run by the tests",
    ),
}
RUN_HERE = {
    ("docs/getting_started.md", "A first decomposition", 0),
    ("README.md", "Python API", 0),
    ("docs/guide/viewer.md", "Looking at a result interactively", 0),
    ("docs/guide/decomposition.md", "Decomposition methods", 0),
    ("docs/guide/graphs.md", "Task graphs with Dask", 0),
    ("docs/guide/pipelines.md", "YAML pipelines", 0),
    ("docs/guide/pipelines.md", "YAML pipelines", 1),
    ("docs/guide/pipelines.md", "YAML pipelines", 2),
    ("docs/guide/cli.md", "Command line", 0),
    ("docs/guide/clusters.md", "Running on a cluster", 1),
}


def test_every_block_is_run_or_mirrored():
    assert set(blocks()) == RUN_HERE | set(MIRRORED)


@pytest.mark.parametrize("key", sorted(MIRRORED), ids=lambda k: f"{k[0]}:{k[1]}#{k[2]}")
def test_a_mirror_names_a_test_that_exists(key):
    path, name = MIRRORED[key].test.split("::")
    assert name in (ROOT / path).read_text(), MIRRORED[key]


@pytest.fixture
def scratch(tmp_path):
    """A folder holding what the blocks name: model.ply, scans/ with two models, out/."""
    shutil.copy(shipped_model_path("spot.ply"), tmp_path / "model.ply")
    (tmp_path / "scans").mkdir()
    for name in ("spot.ply", "sphere_oct4098.ply"):
        shutil.copy(shipped_model_path(name), tmp_path / "scans" / name)
    (tmp_path / "out").mkdir()
    return tmp_path


def _python(code: str, folder: Path) -> subprocess.CompletedProcess:
    script = folder / "snippet.py"
    script.write_text(code)
    env = {"PYTHONPATH": str(ROOT), "PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin"}
    done = subprocess.run(
        [sys.executable, str(script)], cwd=folder, capture_output=True, text=True, timeout=TIMEOUT, env=env
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return done


@pytest.mark.slow
def test_the_python_api_and_viewer_blocks_run(scratch):
    """The viewer block continues the API block (``result``, ``surface``)."""
    code = (
        blocks()[("README.md", "Python API", 0)][1]
        + blocks()[("docs/guide/viewer.md", "Looking at a result interactively", 0)][1]
    )
    _python(code, scratch)
    for name in ("model_hht.ply", "model_hht.npz", "model_hht.html", "pair.html", "f.html"):
        assert (scratch / "out" / name).stat().st_size > 0, name


def test_the_first_decomposition_runs(scratch):
    done = _python(blocks()[("docs/getting_started.md", "A first decomposition", 0)][1], scratch)
    assert done.stdout.startswith("HHTResult('spot': 3 IMFs of 2,930 vertices, shares "), done.stdout
    for name in ("spot_hht.ply", "spot_hht.html"):
        assert (scratch / name).stat().st_size > 0, name


def test_the_decomposition_methods_block_runs(scratch):
    """The filtering example prints its IMF count, an energy ratio at most 1 and a non-negative IO."""
    done = _python(blocks()[("docs/guide/decomposition.md", "Decomposition methods", 0)][1], scratch)
    count, ratio, io = done.stdout.split()
    assert int(count) >= 2 and float(ratio) <= 1 and float(io) >= 0, done.stdout


@pytest.mark.slow
def test_the_task_graph_block_runs(scratch):
    _python(blocks()[("docs/guide/graphs.md", "Task graphs with Dask", 0)][1], scratch)
    assert (scratch / "out" / "model_hht.ply").stat().st_size > 0
    rows = json.loads((scratch / "out" / "summary.json").read_text())
    assert sorted((Path(r["source"]).name, r["status"]) for r in rows) == [
        ("sphere_oct4098.ply", "ok"),
        ("spot.ply", "ok"),
    ]


def _hht3d(*args, folder: Path) -> subprocess.CompletedProcess:
    done = subprocess.run(
        [sys.executable, "-m", "hht3d", *args],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    assert done.returncode == 0, f"hht3d {' '.join(args)}:\n{done.stderr[-3000:]}"
    return done


@pytest.mark.slow
def test_the_yaml_pipeline_block_runs(scratch):
    (scratch / "p.yaml").write_text(blocks()[("docs/guide/pipelines.md", "YAML pipelines", 0)][1])
    _hht3d("run", "p.yaml", folder=scratch)
    written = sorted(p.name for p in (scratch / "out" / "run1").iterdir() if not p.name.startswith("."))
    for stem in ("spot", "sphere_oct4098"):
        assert {
            f"{stem}_hht.ply",
            f"{stem}_hht.png",
            f"{stem}_smooth.ply",
            f"{stem}_hht.html",
            f"{stem}_smooth.html",
        } <= set(written)


def test_the_editor_lines_name_the_shipped_schema():
    comment = blocks()[("docs/guide/pipelines.md", "YAML pipelines", 1)][1]
    relative = comment.split("$schema=")[1].strip()
    assert (ROOT / "pipelines" / relative).resolve() == (ROOT / "hht3d" / "data" / "pipeline.schema.json")
    settings = json.loads(blocks()[("docs/guide/pipelines.md", "YAML pipelines", 2)][1])
    assert all((ROOT / path).is_file() for path in settings["yaml.schemas"])


@pytest.mark.slow
def test_the_command_lines_run(scratch):
    """Each line of the Command line block, in the scratch folder; lines that need another
    scheduler or a pipeline in use elsewhere are the shipped examples' and the storage tests'."""
    (scratch / "p.yaml").write_text(blocks()[("docs/guide/pipelines.md", "YAML pipelines", 0)][1])
    elsewhere = {
        "hht3d run pipelines/filtering.yaml": "tests/test_shipped_examples.py",
        "hht3d demo --out out/demo": "tests/cli/test_cli.py",
        "hht3d run p.yaml --set inputs=scans/ --set steps.hht.params.max_imfs=8 --resume": (
            "tests/pipeline/test_runner.py"
        ),
        "hht3d run p.yaml --scheduler distributed --address tcp://host:8786": "tests/io/test_storage.py",
    }
    lines = [line.split("#")[0].strip() for line in blocks()[("docs/guide/cli.md", "Command line", 0)][1].splitlines()]
    import hht3d
    from hht3d.geometry.signals import mean_curvature

    spot = hht3d.load(scratch / "model.ply")  # the results the view lines read
    result = hht3d.hht(spot, mean_curvature(spot), max_imfs=1)
    result.save(scratch / "out" / "model_hht.npz")
    result.save(scratch / "x.ply")  # `hht3d view x.ply --field imf_1`: a result saved as PLY
    for line in filter(None, lines):
        if line in elsewhere:
            assert (ROOT / elsewhere[line]).is_file()
            continue
        words = line.replace("[OP ...]", "").replace("[--output FILE]", "").replace("[--json]", "--json").split()
        _hht3d(*words[1:], folder=scratch)


def test_the_helm_values_name_extras_hht3d_has():
    values = yaml.safe_load(blocks()[("docs/guide/clusters.md", "Running on a cluster", 1)][1])
    package = next(e["value"] for e in values["worker"]["env"] if e["name"] == "EXTRA_PIP_PACKAGES")
    extras = set(re.fullmatch(r"hht3d\[(.+)\]", package).group(1).split(","))
    declared = set(re.findall(r"^(\w+) = \[", (ROOT / "pyproject.toml").read_text(), re.M))
    assert extras <= declared
