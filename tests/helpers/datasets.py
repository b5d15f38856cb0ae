"""The input folder of the dataset-run tests: two good meshes, a corrupt PLY, three points."""

import numpy as np

from helpers.meshes import icosphere
from hht3d import Surface
from hht3d.io import write_ply


def _make_inputs(folder):
    folder.mkdir()
    v, f = icosphere(3)
    for i, scale in enumerate([1.0, 2.0]):
        bumpy = scale * v * (1 + 0.04 * np.sin((5 + i) * v[:, [0]]))
        write_ply(folder / f"good{i}.ply", Surface(bumpy, f))
    (folder / "corrupt.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n")
    (folder / "three_points.xyz").write_text("0 0 0\n1 0 0\n0 1 0\n")
    return folder
