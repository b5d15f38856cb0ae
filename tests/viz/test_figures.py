"""Figures of HHT results: the Fig. 4 composite, Hilbert spectrum plots and the standard set."""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import pytest

from helpers.images import assert_red_blue_swapped
from helpers.meshes import fibonacci_sphere, icosphere
from hht3d.errors import InputError
from hht3d.geometry.surface import Surface
from hht3d.transform import HHTResult, hht
from hht3d.viz import figures


def two_scale_signal(vertices):
    """Two oscillations around the equator (8 and 3 waves) and a trend: two IMFs and a residue."""
    x, y, z = vertices.T
    azimuth = np.arctan2(y, x)
    return np.cos(8 * azimuth) * (1 - z**2) + 0.8 * np.cos(3 * azimuth + 0.5) * (1 - z**2) ** 1.5 + 0.5 * z


@pytest.fixture(scope="module")
def result() -> HHTResult:
    s = Surface(*icosphere(3), name="sphere")
    return hht(s, two_scale_signal(s.vertices), max_imfs=2)


@pytest.fixture(scope="module")
def cloud_result() -> HHTResult:
    points = fibonacci_sphere(1500)
    s = Surface(points, normals=points, name="cloud")
    return hht(s, two_scale_signal(points), max_imfs=2)


def pixels(path):
    from PIL import Image

    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"), dtype=np.float64)


def test_standard_set_is_written_at_the_requested_sizes(result, tmp_path):
    pyplot_loaded = "matplotlib.pyplot" in sys.modules
    paths = figures.write_figures(
        result,
        tmp_path / "figs",
        hht_size=(900, 520),
        spectrum_size=(700, 300),
        field_size=(400, 360),
        signal_name="test signal",
    )
    assert set(paths) == {"hht", "spectrum", "signal"}
    assert paths["hht"].name == "sphere_hht.png"
    sizes = {"hht": (520, 900), "spectrum": (300, 700), "signal": (360, 400)}
    for name, path in paths.items():
        image = pixels(path)
        assert image.shape[:2] == sizes[name]
        assert image.std() > 20, f"{name} looks blank"
    assert sorted(p.name for p in (tmp_path / "figs").iterdir()) == sorted(p.name for p in paths.values())
    assert pyplot_loaded or "matplotlib.pyplot" not in sys.modules  # no global pyplot state


def test_composite_panels_are_coloured_by_their_fields(result):
    fig = figures.hht_figure(result, panel_width=120)
    k = result.n_imfs
    width, height = (int(round(v)) for v in fig.get_size_inches() * fig.dpi)
    assert width == 120 * (k + 3)
    images = [ax.get_images()[0].get_array() for ax in fig.axes if ax.get_images()]
    assert len(images) == 3 + 3 * k  # model, signal, IMFs, residue; frequency and amplitude rows
    model, imf = np.asarray(images[0], float), np.asarray(images[3], float)  # drawn: model, signal, residue, IMF 1
    on_model = imf.min(axis=2) < 250
    assert on_model.mean() > 0.3
    # the shaded model is grey; an IMF in a diverging map has both red and blue parts
    assert np.allclose(model[..., 0], model[..., 2], atol=12)
    red = imf[..., 0] > imf[..., 2] + 30
    blue = imf[..., 2] > imf[..., 0] + 30
    assert red.mean() > 0.02 and blue.mean() > 0.02


def negated(result: HHTResult) -> HHTResult:
    """The HHT of −f, written from the definitions: IMFs, residue and Riesz vectors change sign,
    the phase φ becomes π − φ, the amplitude and frequency stay."""
    mono = result.monogenic
    flipped = dataclasses.replace(mono, imfs=-mono.imfs, riesz=-mono.riesz, phase=np.pi - mono.phase)
    return dataclasses.replace(
        result, signal=-result.signal, imfs=-result.imfs, residue=-result.residue, monogenic=flipped
    )


def test_composite_panels_show_their_own_fields(result):
    # Panels in drawing order: model, signal, residue, then IMF, ω and a of each IMF.  For −f the
    # IMF panels (diverging map, symmetric limits) swap red and blue, the ω and a panels and the
    # model are pixel for pixel the same, and different IMFs give different pictures.
    def panels(r):
        fig = figures.hht_figure(r, panel_width=100)
        return [np.asarray(ax.get_images()[0].get_array(), float) for ax in fig.axes if ax.get_images()]

    plain, flipped = panels(result), panels(negated(result))
    k = result.n_imfs
    assert np.array_equal(plain[0], flipped[0])
    for i in range(k):
        imf, frequency, amplitude = (3 + 3 * i, 4 + 3 * i, 5 + 3 * i)
        assert np.array_equal(plain[frequency], flipped[frequency])
        assert np.array_equal(plain[amplitude], flipped[amplitude])
        coloured = np.abs(plain[imf][..., 0] - plain[imf][..., 2]) > 30
        assert coloured.mean() > 0.05
        assert_red_blue_swapped(plain[imf], flipped[imf], coloured)
    assert not np.array_equal(plain[3], plain[6])  # IMF 1 and IMF 2 are different fields


def test_composite_default_height_fits_the_model(result):
    tall_surface = Surface(result.surface.vertices * [1.0, 2.0, 1.0], result.surface.faces, name="tall")
    tall = dataclasses.replace(result, surface=tall_surface)

    def image_aspect(fig):
        box = fig.axes[0].get_position()  # the model's panel
        width, height = fig.get_size_inches()
        return box.height * height / (box.width * width)

    aspects = [image_aspect(figures.hht_figure(r, panel_width=100)) for r in (result, tall)]
    assert aspects[0] == pytest.approx(1.0, abs=0.05) and aspects[1] == pytest.approx(2.0, abs=0.1)


def test_point_cloud_result(cloud_result, tmp_path):
    from hht3d.viz.panels import render_png

    paths = figures.write_figures(cloud_result, tmp_path, stem="pc", hht_size=(700, 420), field_size=(400, 360))
    assert pixels(paths["hht"]).shape[:2] == (420, 700)
    # the signal figure shows the signal on the points: rendered again for −f with the same title
    # (the signed signal gets symmetric limits, so the colour bar is the same), only the splats
    # change, and red and blue swap there
    other = render_png(
        tmp_path / "negated.png", cloud_result.surface, -cloud_result.signal, size=(400, 360), title="cloud: signal"
    )
    changed = assert_red_blue_swapped(pixels(paths["signal"]), pixels(other))
    assert 0.1 < changed.mean() < 0.7


def test_spectrum_shares(result):
    fig = figures.spectrum_figure(result, bins=32, scale="linear", size=(600, 300))
    left, right = fig.axes[:2]
    marginal = left.patches[-1].get_data()[0]
    per_imf = [p.get_data()[0] for p in right.patches]
    assert len(per_imf) == result.n_imfs
    assert 95 < marginal.sum() <= 100.0 + 1e-9
    assert np.allclose(np.sum(per_imf, axis=0), marginal)
    assert figures.spectrum_figure(result, scale="log").axes[0].get_xscale() == "log"


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda r: figures.hht_figure("not a result"), "HHTResult"),
        (lambda r: figures.hht_figure(r, size=(50, 50)), "larger"),
        (lambda r: figures.hht_figure(r, view="under"), "unknown view"),
        (lambda r: figures.hht_figure(r, dpi=0), "dpi"),
        (lambda r: figures.spectrum_figure(r, scale="mel"), "scale"),
        (lambda r: figures.spectrum_figure(r, bins=0), "bins"),
        (lambda r: figures.spectrum_figure(r, size=(10, -1)), "size"),
    ],
)
def test_bad_parameters_raise_input_error(result, call, message):
    with pytest.raises(InputError, match=message):
        call(result)
