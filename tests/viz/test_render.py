"""Headless rendering of per-vertex fields: cameras, colours, z-buffer, point splats, PNGs."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from helpers.meshes import fibonacci_sphere
from hht3d.errors import InputError
from hht3d.geometry.surface import Surface
from hht3d.viz import panels
from hht3d.viz import render as R


@pytest.fixture(scope="module")
def cloud() -> Surface:
    points = fibonacci_sphere(4000)
    return Surface(points, normals=points, name="cloud")


def red_over_blue(rendering, mask) -> float:
    """Share of the masked model pixels that are redder than blue."""
    rgb = rendering.rgba[..., :3][mask & rendering.mask]
    return float(np.mean(rgb[:, 0] > rgb[:, 2]))


def halves(shape):
    columns = np.arange(shape[1])[None, :].repeat(shape[0], axis=0)
    return columns < shape[1] // 2, columns >= shape[1] // 2


@pytest.mark.parametrize("fixture", ["sphere", "cloud"])
def test_field_colours_follow_x(fixture, request):
    surface = request.getfixturevalue(fixture)
    image = R.render(surface, surface.vertices[:, 0], size=(160, 120), cmap="RdBu_r", symmetric=True)
    assert image.rgba.shape == (120, 160, 4) and image.backend == "software"
    left, right = halves(image.mask.shape)
    assert red_over_blue(image, left) < 0.1 and red_over_blue(image, right) > 0.9
    # framed: the model is centred and fills the height; corners are background
    rgb = image.rgb()
    assert image.mask[60, 80] and not image.mask[0, 0] and not image.mask[-1, -1]
    assert np.all(rgb[0, 0] == 255) and rgb[image.mask].std() > 10
    assert 0.4 < image.mask.mean() < 0.75
    assert image.mask[:, 80].sum() > 0.85 * 120


@pytest.mark.parametrize(
    ("view", "up", "axis", "red"),
    [
        ("right", "y", 0, 1.0),
        ("left", "y", 0, 0.0),
        ("back", "y", 2, 0.0),
        ("front", "y", 2, 1.0),
        ("top", "y", 1, 1.0),
        ("bottom", "y", 1, 0.0),
        ((90.0, 0.0), "y", 0, 1.0),
        ("front", "z", 1, 0.0),
    ],
)
def test_views_see_the_named_side(sphere, view, up, axis, red):
    image = R.render(sphere, sphere.vertices[:, axis], view=view, up=up, size=(64, 64), cmap="RdBu_r", symmetric=True)
    assert abs(red_over_blue(image, np.ones((64, 64), bool)) - red) < 0.05


def test_up_axis_puts_that_axis_at_the_top(sphere):
    image = R.render(sphere, sphere.vertices[:, 2], up="z", size=(64, 64), cmap="RdBu_r", symmetric=True)
    rows = np.arange(64)[:, None].repeat(64, axis=1)
    assert red_over_blue(image, rows < 28) > 0.95 and red_over_blue(image, rows > 36) < 0.05


def test_nearer_surface_hides_the_farther_one():
    # a small near square (value 1) drawn before a large far square (value 0) behind it
    near = np.array([[-0.5, -0.5, 1], [0.5, -0.5, 1], [0.5, 0.5, 1], [-0.5, 0.5, 1]], float)
    far = np.array([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], float)
    quads = np.array([[0, 1, 2], [0, 2, 3]])
    mesh = Surface(np.vstack([near, far]), np.vstack([quads, quads + 4]))
    values = np.r_[np.ones(4), np.zeros(4)]
    image = R.render(mesh, values, size=(80, 80), cmap="RdBu_r", limits=(0, 1), supersample=1)
    red, _, blue = image.rgba[40, 40, :3]
    assert red > 2 * blue  # centre: the near square (value 1, dark red)
    red, _, blue = image.rgba[10, 10, :3]
    assert blue > 2 * red  # outside it: the far square (value 0, dark blue)
    assert image.mask.mean() > 0.85  # the far square fills the frame but its margin


def test_shaded_model_and_antialiased_edges(sphere):
    image = R.render(sphere, size=(90, 90))
    assert image.scale is None
    alpha = image.rgba[..., 3]
    assert np.any((alpha > 0.1) & (alpha < 0.9))  # supersampled silhouette
    lit = image.rgba[..., :3][image.mask].mean(axis=1)
    assert lit.max() - lit.min() > 0.3  # Lambert shading varies over the sphere


def test_nan_values_are_grey(sphere):
    values = sphere.vertices[:, 0].copy()
    values[:] = np.nan
    values[0] = 0.0
    image = R.render(sphere, values, size=(40, 40), limits=(-1, 1))
    rgb = image.rgba[..., :3][image.mask]
    assert np.allclose(rgb[:, 0], rgb[:, 2], atol=0.02)


def test_color_scale_robust_and_symmetric():
    rng = np.random.default_rng(0)
    values = np.r_[rng.normal(0, 1, 10_000), 1e6]
    scale = R.color_scale(values)
    assert scale.cmap == "RdBu_r" and scale.vmin == -scale.vmax and 2 < scale.vmax < 3
    positive = R.color_scale(np.abs(values))
    assert positive.cmap == "viridis" and positive.vmin >= 0 and positive.vmax < 4
    assert R.color_scale(np.full(5, 3.0)).vmin < 3.0 < R.color_scale(np.full(5, 3.0)).vmax
    assert R.color_scale(values, limits=(0, 2), cmap="magma") == R.ColorScale("magma", 0.0, 2.0)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda s: R.render(s, view="sideways"), "unknown view"),
        (lambda s: R.render(s, view=(1.0,)), "azimuth"),
        (lambda s: R.render(s, up="w"), "up axis"),
        (lambda s: R.render(s, up=(0, 0, 0)), "up must be"),
        (lambda s: R.render(s, s.vertices[:, 0], cmap="nope"), "colour map"),
        (lambda s: R.render(s, s.vertices[:, 0], limits=(1, 0)), "limits"),
        (lambda s: R.render(s, np.zeros(3)), "one value per vertex"),
        (lambda s: R.render(s, size=(0, 10)), "size"),
        (lambda s: R.render(s, size=(10.5, 10)), "size"),
        (lambda s: R.render(s, backend="povray"), "unknown render backend"),
        (lambda s: R.render(s, supersample=9), "supersample"),
        (lambda s: panels.render_png("x.jpg", s), "PNG"),
    ],
)
def test_bad_parameters_raise_input_error(sphere, call, message):
    with pytest.raises(InputError, match=message):
        call(sphere)


OPEN3D_CHECK = """
import sys
import numpy as np
sys.path.insert(0, {tests!r})
from helpers.images import assert_red_blue_swapped
from hht3d.viz import figures, panels
from hht3d.viz import render as R
from hht3d.errors import InputError
from hht3d.geometry.surface import Surface
from helpers.meshes import icosphere
sphere = Surface(*icosphere(3))
try:
    first = R.renderer(sphere, size=(96, 64), backend="open3d")
except InputError as exc:
    assert "unavailable" in str(exc), exc
    print("unavailable")
    sys.exit(0)
image = first.render(sphere.vertices[:, 0], R.color_scale(sphere.vertices[:, 0], cmap="RdBu_r"))
second = R.renderer(sphere, size=(40, 40), backend="open3d", view="right")  # one offscreen at a time
assert second.render().rgba.shape == (40, 40, 4)
assert image.rgba.shape == (64, 96, 4) and image.backend == "open3d"
rgb, mask = image.rgba[..., :3], image.mask
red = rgb[..., 0] > rgb[..., 2]
assert red[:, :48][mask[:, :48]].mean() < 0.1 and red[:, 48:][mask[:, 48:]].mean() > 0.9
assert not mask[0, 0] and mask[32, 48]
del first, second
print("rendered")
"""


def test_open3d_backend_renders_or_explains():
    """In a child process: Filament can abort or hang a process, which must not take pytest with it."""
    import subprocess
    from pathlib import Path

    script = OPEN3D_CHECK.format(tests=str(Path(__file__).parents[1]))
    try:
        done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=90)
    except subprocess.TimeoutExpired:
        pytest.skip("Open3D's offscreen renderer hung in the child process (Filament)")
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split()[-1] in ("rendered", "unavailable")
