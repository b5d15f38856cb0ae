"""PNG panels of a field (hht3d.viz.panels): the requested size, no pyplot state, the field's colours."""

from __future__ import annotations

import sys

import numpy as np

from helpers.images import assert_red_blue_swapped
from hht3d.viz import panels


def test_render_png_has_the_requested_size(sphere, tmp_path):
    from PIL import Image

    pyplot_loaded = "matplotlib.pyplot" in sys.modules
    path = panels.render_png(
        tmp_path / "x.png", sphere, sphere.vertices[:, 0], title="x", label="x (m)", size=(420, 300), dpi=90
    )
    with Image.open(path) as image:
        assert image.size == (420, 300)
        pixels = np.asarray(image.convert("RGB"), dtype=float)
    assert pixels.std() > 20
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left
    assert pyplot_loaded or "matplotlib.pyplot" not in sys.modules  # no global pyplot state
    # the PNG shows the field: with −x (same symmetric limits, so the same title and colour bar)
    # only the model's pixels change, red and blue swap there, and red lies right of blue (the
    # front view looks down −z with y up, so x grows to the right)
    other = panels.render_png(
        tmp_path / "y.png",
        sphere,
        -sphere.vertices[:, 0],
        title="x",
        label="x (m)",
        size=(420, 300),
        dpi=90,
        limits=(-1, 1),
        cmap="RdBu_r",
    )
    path = panels.render_png(
        tmp_path / "x.png",
        sphere,
        sphere.vertices[:, 0],
        title="x",
        label="x (m)",
        size=(420, 300),
        dpi=90,
        limits=(-1, 1),
        cmap="RdBu_r",
    )
    with Image.open(path) as image, Image.open(other) as flipped:
        a, b = (np.asarray(i.convert("RGB"), dtype=float) for i in (image, flipped))
    changed = assert_red_blue_swapped(a, b)
    assert 0.1 < changed.mean() < 0.6
    warm = a[..., 0] - a[..., 2]
    columns = np.nonzero(changed)[1]
    assert columns[warm[changed] > 0].mean() > columns[warm[changed] < 0].mean() + 30
