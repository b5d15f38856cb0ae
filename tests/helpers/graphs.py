"""Surfaces and settings of the lazy-graph tests, and the task-name prefix of a graph key."""

import numpy as np

from helpers.meshes import fibonacci_sphere, icosphere
from hht3d import Surface

OPTIONS = dict(max_imfs=3, riesz_tasks=3)


def _surfaces():
    v, f = icosphere(3)
    bumpy = v * (1 + 0.05 * np.sin(5 * v[:, [0]]) * np.cos(4 * v[:, [1]]))
    return [Surface(bumpy, f, name="mesh"), Surface(fibonacci_sphere(1500) * 1.3, name="cloud")]


def _prefix(key) -> str:
    name = key[0] if isinstance(key, tuple) else key
    return name.rsplit("-", 1)[0]
