"""Hilbert-spectrum filtering (Eq. 26, hht3d.apps.filters): the gains, and the filtered signal."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from helpers.bumps import OMEGA
from helpers.meshes import bump_band_sphere
from hht3d import InputError, Surface
from hht3d.apps import (
    BandBoost,
    BandStop,
    Constant,
    HighBoost,
    LowPass,
    PiecewiseLinear,
    filter_signal,
    gains_of,
    make_gain,
)
from hht3d.geometry.signals import mean_curvature
from hht3d.transform import hht

# -- gains ---------------------------------------------------------------------------------


def test_gain_shapes():
    omega = np.array([0.0, 5.0, 10.0, 10.5, 20.0, 30.0, 40.0])
    assert LowPass(cutoff=10.0)(omega).tolist() == [1, 1, 1, 0, 0, 0, 0]
    assert LowPass(cutoff=10.0, stop=0.25)(omega)[-1] == 0.25
    assert HighBoost(cutoff=10.0, factor=3.0)(omega).tolist() == [1, 1, 1, 3, 3, 3, 3]
    assert BandStop(low=5.0, high=20.0)(omega).tolist() == [1, 1, 0, 0, 0, 1, 1]
    assert BandBoost(low=5.0, high=20.0, factor=2.5)(omega).tolist() == [1, 1, 2.5, 2.5, 2.5, 1, 1]
    assert Constant(0.5)(omega).tolist() == [0.5] * 7
    # user points: linear between, constant beyond
    user = PiecewiseLinear([(10.0, 1.0), (30.0, 3.0)])
    assert np.allclose(user(omega), [1, 1, 1, 1.05, 2, 3, 3])
    # raised-cosine edges: half-way at the edge, flat beyond edge ± width/2, monotone between
    smooth = LowPass(cutoff=10.0, width=4.0)
    assert smooth(np.array([7.9, 8.0, 10.0, 12.0, 12.1])).tolist() == pytest.approx([1, 1, 0.5, 0, 0])
    assert np.all(np.diff(smooth(np.linspace(7, 13, 50))) <= 0)
    band = BandStop(low=5.0, high=20.0, width=2.0)
    assert band(np.array([3.9, 5.0, 6.0, 12.0, 19.0, 20.0, 21.0])).tolist() == pytest.approx([1, 0.5, 0, 0, 0, 0.5, 1])


def test_gains_pickle_and_by_name():
    gains = [
        LowPass(cutoff=3.0, width=1.0),
        HighBoost(cutoff=2.0, factor=2.5),
        BandStop(low=1.0, high=2.0),
        BandBoost(low=1.0, high=2.0, factor=3.0),
        PiecewiseLinear([(0.0, 1.0), (5.0, 0.0)]),
        Constant(1.0),
    ]
    omega = np.linspace(0, 10, 11)
    for gain in gains:
        back = pickle.loads(pickle.dumps(gain))
        assert back == gain and np.array_equal(back(omega), gain(omega))
    assert make_gain("band_stop", low=1.0, high=2.0) == BandStop(low=1.0, high=2.0)
    assert make_gain("piecewise_linear", points=[[0, 1], [5, 0]]) == gains[4]


def test_filter_signal_is_eq26(bumps):
    result = bumps[3]
    mono = result.monogenic
    gain = BandStop(low=OMEGA / 2, high=2 * OMEGA, width=OMEGA / 4)
    expected = np.sum(gain(mono.frequency) * mono.amplitude * np.cos(mono.phase), axis=0) + result.residue
    assert np.allclose(filter_signal(result, gain), expected, rtol=0, atol=1e-12 * np.abs(result.signal).max())
    # tuple input, identity, all-stop, any callable
    parts = (result.imfs, result.residue, mono)
    assert np.allclose(
        filter_signal(parts, Constant(1.0)), result.signal, rtol=0, atol=1e-13 * np.abs(result.signal).max()
    )
    assert np.array_equal(filter_signal(parts, Constant(0.0)), result.residue)
    assert np.array_equal(
        filter_signal(parts, lambda w: np.where(w > 5, 2.0, 1.0)),
        filter_signal(parts, HighBoost(cutoff=5.0, factor=2.0)),
    )
    assert gains_of(result, gain).shape == result.imfs.shape


def test_filtering_does_not_depend_on_the_signal_unit():
    """The gains read the instantaneous frequency ω = |∇φ|, a rate of the phase φ = atan2(|Rf|, f),
    which does not change when the signal is multiplied by c (EMD's thresholds are relative, the
    Riesz transform is linear): the HHT of c·s gives the same gains and c times the filtered signal,
    whatever the IMF amplitudes (0.2-0.7 here).  Only round-off differs: measured 9e-13 in the
    gains and 2e-14 of max |c·s| in s', bounds 1e-11 and 2e-13."""
    v, f, _, _ = bump_band_sphere(4, 12, 0.01)
    surface = Surface(v, f)
    signal = mean_curvature(surface)
    omega = np.sqrt(12 * 13)
    gain = BandStop(low=omega / 2, high=2 * omega, width=omega / 4)
    reference = hht(surface, signal, max_imfs=3)
    for c in (1e3, -1e-3):
        scaled = hht(surface, c * signal, max_imfs=3)
        assert np.abs(gains_of(scaled, gain) - gains_of(reference, gain)).max() <= 1e-11
        error = np.abs(filter_signal(scaled, gain) - c * filter_signal(reference, gain)).max()
        assert error <= 2e-13 * np.abs(c * signal).max()


# -- bad parameters --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "build",
    [
        lambda: LowPass(cutoff=-1.0),
        lambda: LowPass(cutoff=float("nan")),
        lambda: LowPass(cutoff=1.0, width=-1),
        lambda: HighBoost(cutoff=1.0, factor=float("inf")),
        lambda: BandStop(low=5.0, high=5.0),
        lambda: BandBoost(low=6.0, high=2.0),
        lambda: PiecewiseLinear([]),
        lambda: PiecewiseLinear([(2.0, 1.0), (1.0, 0.0)]),
        lambda: PiecewiseLinear([(0.0, 1.0, 2.0)]),
        lambda: PiecewiseLinear([(-1.0, 1.0)]),
        lambda: LowPass(cutoff="high"),
        lambda: make_gain("notch", low=1),
        lambda: make_gain("low_pass", cut=1),
    ],
)
def test_bad_gains(build):
    with pytest.raises(InputError):
        build()
