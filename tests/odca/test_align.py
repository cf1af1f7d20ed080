"""Robust LiDAR alignment."""

import numpy as np
import pytest

from racf.odca import fit_alignment


def test_recovers_the_affine_map_despite_outliers():
    rng = np.random.default_rng(0)
    l = rng.uniform(0.3, 3.0, 400)
    d = 0.97 * l - 0.11 + rng.normal(0, 0.005, 400)
    d[:40] += rng.uniform(0.5, 2.0, 40)  # attacked / wrong-object samples
    a = fit_alignment(d, l)
    assert a.alpha == pytest.approx(0.97, abs=0.01) and a.beta == pytest.approx(-0.11, abs=0.01)
    np.testing.assert_allclose(a(np.array([1.0])), [a.alpha + a.beta])


def test_low_confidence_and_invalid_samples_are_dropped_and_too_few_is_an_error():
    l = np.linspace(0.5, 2.0, 30)
    d = l + 0.1
    c = np.r_[np.ones(25), np.zeros(5)]
    d_bad = d.copy()
    d_bad[25:] = 9.0
    assert fit_alignment(d_bad, l, c).beta == pytest.approx(0.1, abs=1e-3)
    with pytest.raises(ValueError, match="need >= 20"):
        fit_alignment(d[:10], l[:10])
    with pytest.raises(ValueError, match="same length"):
        fit_alignment(d, l[:5])
