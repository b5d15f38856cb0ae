"""EEMD (hht3d.decomposition.ensemble): seeded, the noise each member carries, their average."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.emd import assert_sums_to_signal, real_sph_harm
from hht3d.decomposition import EMDOptions, EnsembleOptions, combine_eemd, eemd, eemd_member, emd

# -- EEMD ----------------------------------------------------------------------------------


def test_eemd_seeded(small_sphere):
    f = real_sph_harm(7, np.arange(15.0), small_sphere.vertices)
    options = dict(ensemble_size=3, max_imfs=3)
    first = eemd(small_sphere, f, seed=11, **options)
    again = eemd(small_sphere, f, seed=11, **options)
    other = eemd(small_sphere, f, seed=12, **options)
    np.testing.assert_array_equal(first.imfs, again.imfs)
    np.testing.assert_array_equal(first.residue, again.residue)
    assert first.imfs.shape != other.imfs.shape or not np.allclose(first.imfs, other.imfs)
    assert_sums_to_signal(first, f)
    assert first.info["ensemble_size"] == 3


def test_eemd_without_noise_is_emd_and_members_carry_their_noise(small_sphere):
    # With zero noise every member is the plain EMD, so their average is too (to round-off of the
    # averaging); a wrong divisor or member order breaks it.
    f = real_sph_harm(5, np.arange(11.0), small_sphere.vertices)
    quiet = eemd(small_sphere, f, ensemble_size=3, noise_std=0.0, seed=5, max_imfs=2)
    plain = emd(small_sphere, f, max_imfs=2)
    np.testing.assert_allclose(quiet.imfs, plain.imfs, rtol=0, atol=1e-12 * np.abs(f).max())
    # each member decomposes signal + its own noise, of std 0.2 * std(f) (642 samples: ±3σ ≈ ±17%)
    member = eemd_member(small_sphere, f, 1, EMDOptions(max_imfs=2), EnsembleOptions(seed=5, noise_std=0.2))
    noise = member.imfs.sum(axis=0) + member.residue - f
    assert 0.17 < np.std(noise) / np.std(f) < 0.23
    other = eemd_member(small_sphere, f, 0, EMDOptions(max_imfs=2), EnsembleOptions(seed=5, noise_std=0.2))
    assert abs(np.corrcoef(noise, other.imfs.sum(axis=0) + other.residue - f)[0, 1]) < 0.15  # independent
    combined = combine_eemd(small_sphere, f, [member, other])
    np.testing.assert_allclose(combined.imfs[:2], (member.imfs[:2] + other.imfs[:2]) / 2, rtol=0, atol=1e-15)


def test_eemd_member_takes_the_records_in_eemds_order(small_sphere):
    f = small_sphere.vertices[:, 0]
    options, ensemble = EMDOptions(max_imfs=1), EnsembleOptions(seed=2)
    member = eemd_member(small_sphere, f, 0, options, ensemble)
    with pytest.warns(DeprecationWarning, match="EMD options first"):
        former = eemd_member(small_sphere, f, 0, ensemble, options)
    np.testing.assert_array_equal(former.imfs, member.imfs)
