"""Prominent features from IMF extrema (Sec. 5.2) and the heat-kernel-signature baseline."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

import hht3d
from helpers.meshes import grid, icosphere
from hht3d import InputError, Surface
from hht3d.apps import (
    FEATURE_EMD_OPTIONS,
    FeatureResult,
    heat_kernel_signature,
    hks_features,
    merge_hits,
    prominent_features,
    repeatability,
)
from hht3d.cli import demo_model_path
from hht3d.decomposition import emd, local_extrema
from hht3d.geometry.signals import mean_curvature


def mean_edge_length(surface: Surface) -> float:
    p = surface.vertices[surface.faces]
    return float(np.mean(np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2)))


@pytest.fixture(scope="module")
def spot():
    """The shipped demo model (2,930 vertices) and its mean-curvature EMD, as features take it."""
    surface = hht3d.load(demo_model_path())
    return surface, emd(surface, mean_curvature(surface), FEATURE_EMD_OPTIONS)


# -- counting and merging -----------------------------------------------------------------------


def test_counts_threshold_and_per_imf_extrema():
    surface = Surface(*grid(9, 9, jitter=0.1, seed=2))
    x, y = surface.vertices[:, 0], surface.vertices[:, 1]
    imfs = np.array(
        [
            np.cos(2 * np.pi * x) * np.cos(2 * np.pi * y),
            np.cos(4 * np.pi * x) * np.cos(4 * np.pi * y),
            np.sin(3 * np.pi * x) + 0.1 * y,
        ]
    )
    result = prominent_features(surface, imfs)
    assert isinstance(result, FeatureResult) and result.n_scales == 3 and result.min_count == 2
    expected = np.zeros(surface.n_vertices, dtype=int)
    for k, f in enumerate(imfs):
        maxima, minima = local_extrema(surface, f, extrema="relaxed", ring=2, ratio=0.8)
        assert np.array_equal(result.maxima[k], maxima) and np.array_equal(result.minima[k], minima)
        expected[np.union1d(maxima, minima)] += 1
    assert np.array_equal(result.vertex_counts, expected)
    assert np.array_equal(result.vertices, np.flatnonzero(expected >= 2))
    assert np.array_equal(result.counts, expected[result.vertices])
    assert np.array_equal(result.points, surface.vertices[result.vertices])
    assert len(result.vertices) > 0
    # fraction 1: only vertices that are extrema of every IMF
    strict = prominent_features(surface, imfs, fraction=1.0)
    assert strict.min_count == 3 and np.array_equal(strict.vertices, np.flatnonzero(expected == 3))


def test_merge_hits():
    points = np.array([[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0], [5, 0, 0], [5.2, 0, 0], [9, 9, 9]], float)
    scores = np.array([1, 3, 3, 2, 2, 1])
    reps, groups = merge_hits(points, scores, radius=0.6)
    # chain 0-1-2 merges transitively, best score 3 with the first index (1); 3-4 tie -> 3
    assert reps.tolist() == [1, 3, 5]
    assert groups.tolist() == [0, 0, 0, 1, 1, 2]
    assert merge_hits(points, scores, 0.0)[0].tolist() == list(range(6))
    surface = Surface(*icosphere(3))
    f = surface.vertices[:, 2] + 0.05 * np.cos(12 * surface.vertices[:, 0])
    plain = prominent_features(surface, f[None], fraction=1.0)
    merged = prominent_features(surface, f[None], fraction=1.0, merge_radius=0.5)
    assert merged.n_features < plain.n_features and set(merged.vertices) <= set(plain.vertices)
    assert np.array_equal(merged.hits, plain.vertices) and merged.groups.max() == merged.n_features - 1


def test_repeatability_measure():
    a = np.array([[0, 0, 0], [1, 0, 0], [5, 5, 5]], float)
    b = np.array([[0.1, 0, 0], [1, 0.2, 0]])
    assert repeatability(a, b, 0.25) == pytest.approx(2 / 3)
    assert repeatability(b, a, 0.25) == 1.0
    assert repeatability(a, np.empty((0, 3)), 1.0) == 0.0
    assert np.isnan(repeatability(np.empty((0, 3)), a, 1.0))


# -- invariance and noise ----------------------------------------------------------------------


def test_features_invariant_to_rotation_and_scale(spot):
    surface, decomposition = spot
    rotation = Rotation.from_euler("xyz", [0.3, -1.1, 2.0]).as_matrix()
    reference = prominent_features(surface, decomposition)
    assert reference.n_features > 0
    for c in (2.5, 1e-3):
        moved = Surface(c * surface.vertices @ rotation.T + [1.0, -2.0, 3.0], surface.faces)
        result = prominent_features(moved, emd(moved, mean_curvature(moved), FEATURE_EMD_OPTIONS))
        assert np.array_equal(result.vertices, reference.vertices)
        assert np.array_equal(result.vertex_counts, reference.vertex_counts)
        hks_moved = hks_features(moved, eigenpairs=60)
        assert np.array_equal(hks_moved.vertices, hks_features(surface, eigenpairs=60).vertices)


def significance(hits: int, trials: int, chance: np.ndarray) -> float:
    """z-score of ``hits`` successes out of ``trials`` against independent chance rates.

    Poisson-binomial null model with its normal approximation: ``(k − Σp) / √Σp(1−p)``.
    """
    chance = np.broadcast_to(chance, (trials,))
    return float((hits - chance.sum()) / np.sqrt(np.sum(chance * (1 - chance))))


def test_noise_repeatability(spot):
    """Paper Fig. 8: Gaussian noise of 15% of the mean edge length, three noise seeds.

    Features of a noisy copy are mapped to the clean positions (same vertex order) and count as
    repeated within 2 mean edge lengths of a feature of the other copy.  Null model: features
    placed independently of the other copy's land that close with the chance rate, the fraction
    of all vertices that close to it.  Pooled over the seeds, the repeated count must exceed
    chance at significance 1e-3 (z ≥ 3.1) in both directions, for ours and for HKS.  One seed is
    not enough: our noisy feature count varies 22-58 with the seed.  Measured z: ours 13.7
    noisy->clean, 10.2 clean->noisy (with the cancellation guard on: 4.1 and 2.2); HKS 17.9.
    """
    surface, decomposition = spot
    h = mean_edge_length(surface)
    p = surface.vertices
    clean = prominent_features(surface, decomposition).vertices
    hks_clean = hks_features(surface, eigenpairs=60).vertices
    tallies = {name: [0, 0, []] for name in ("forward", "backward", "hks")}

    def tally(name, found, reference):
        near = cKDTree(p[reference])
        tallies[name][0] += int(np.sum(near.query(p[found])[0] <= 2 * h))
        tallies[name][1] += len(found)
        tallies[name][2] += [np.mean(near.query(p)[0] <= 2 * h)] * len(found)

    for seed in range(3):
        rng = np.random.default_rng(seed)
        noisy = Surface(p + rng.normal(scale=0.15 * h, size=p.shape), surface.faces)
        found = prominent_features(noisy, emd(noisy, mean_curvature(noisy), FEATURE_EMD_OPTIONS)).vertices
        tally("forward", found, clean)
        tally("backward", clean, found)
        tally("hks", hks_features(noisy, eigenpairs=60).vertices, hks_clean)
    z = {name: significance(hits, trials, np.array(chance)) for name, (hits, trials, chance) in tallies.items()}
    print(f"\nrepeatability under 15% noise, z-scores against chance: {z}")
    assert all(value >= 3.1 for value in z.values()), z


# -- bad parameters --------------------------------------------------------------------------


def test_bad_parameters(spot):
    surface, decomposition = spot
    for options in (
        {"fraction": 0.0},
        {"fraction": 1.5},
        {"ratio": 0.3},
        {"ring": 0},
        {"merge_radius": -1.0},
        {"merge_radius": float("nan")},
    ):
        with pytest.raises(InputError):
            prominent_features(surface, decomposition, **options)
    with pytest.raises(InputError):
        prominent_features(surface, np.zeros((0, surface.n_vertices)))
    with pytest.raises(InputError):
        prominent_features(surface, decomposition.imfs[:, :-1])
    with pytest.raises(InputError):
        prominent_features(surface.vertices, decomposition)
    for options in ({"eigenpairs": 0}, {"time": -1.0}, {"eigenpairs": 2.5}):
        with pytest.raises(InputError):
            hks_features(surface, **options)
    with pytest.raises(InputError):
        heat_kernel_signature(surface, [0.1, np.inf])
    with pytest.raises(InputError):
        repeatability(np.zeros((1, 3)), np.zeros((1, 3)), -2.0)
