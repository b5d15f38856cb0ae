"""The pipeline and output-format tests' shared parts: the shipped examples, a bumpy sphere file, a good
pipeline to break, a run through the CLI, and what an output file must hold."""

from pathlib import Path

import numpy as np

from helpers.meshes import bumpy_sphere
from helpers.pages import field_values, page_data
from hht3d import Surface
from hht3d.cli import main
from hht3d.io import load, write_ply
from hht3d.pipeline import load_pipeline

EXAMPLES = sorted((Path(__file__).resolve().parents[2] / "pipelines").glob("*.yaml"))
FAST = ["--scheduler", "synchronous", "--quiet"]


def bumpy_file(folder: Path) -> Path:
    """``folder/bumpy.ply``: the bumpy sphere of :func:`helpers.meshes.bumpy_sphere` (162 vertices)."""
    folder.mkdir(parents=True, exist_ok=True)
    return write_ply(folder / "bumpy.ply", Surface(*bumpy_sphere(), name="bumpy"))


def assert_output_fits(path: Path, n_vertices: int) -> None:
    """An output file holds data of its input: per-vertex arrays of the right length, finite
    values, a PLY with every vertex, an HTML page whose fields have every vertex, a PNG
    that is not blank."""
    assert path.is_file(), path
    if path.suffix == ".npz":
        with np.load(path) as data:
            per_vertex = [
                k
                for k in data.files
                if data[k].ndim >= 1
                and data[k].shape[-1] == n_vertices
                or data[k].ndim >= 1
                and len(data[k]) == n_vertices
            ]
            assert per_vertex, (path, data.files)
            for key in data.files:  # numbers are finite (a result also names its Laplacian)
                assert not np.issubdtype(data[key].dtype, np.number) or np.all(np.isfinite(data[key])), (path, key)
    elif path.suffix == ".ply":
        surface = load(path, clean=False)
        assert surface.n_vertices == n_vertices, path
        for key, values in surface.attributes.items():
            assert values.shape == (n_vertices,) and np.all(np.isfinite(values)), (path, key)
    elif path.suffix == ".html":
        data = page_data(path)  # test inputs are far below the viewer's decimation budget
        for spec in data["fields"]:
            values = field_values(data, spec["name"])
            assert np.all(np.isfinite(values)) and len(values) == n_vertices, (path, spec["name"])
    else:
        from PIL import Image

        with Image.open(path) as image:
            assert np.asarray(image.convert("L"), dtype=float).std() > 10, path


def _run(pipeline, *options):
    return main(["run", str(pipeline), *FAST, *options])


def _fast_overrides(path) -> list[str]:
    """Few IMFs for every decomposition of an example, to keep the tests short."""
    plan = load_pipeline(path, ["inputs={builtin: spot}"])  # any input will do here
    return [f"steps.{s.id}.params.max_imfs=2" for s in plan.steps if s.op.name in ("emd", "eemd", "hht")]


GOOD = """\
version: 1
inputs: {mesh}
steps:
  - id: curvature
    op: signal
    params: {{kind: mean_curvature}}
  - id: emd
    op: emd
    params: {{max_imfs: 2}}
outputs:
  folder: {out}
  files:
    - {{from: emd, path: "{{stem}}_imfs.npz"}}
"""
