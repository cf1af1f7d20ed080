"""``ConfidenceDegradation``: drops a share of the sign's depth pixels and adds noise to the rest."""

import numpy as np
import pytest

from racf.sim.attacks import ConfidenceDegradation


def test_confidence_degradation_removes_the_share_and_adds_noise(stub_env, drive, grown):
    env = ConfidenceDegradation(stub_env(), confidence_multiplier=0.3, noise_std_m=0.1, duration_s=5.0,
                                trigger="always")
    kept, errors = [], []
    for obs, clean, info in drive(env, 20):
        region = grown(info["sign_mask"], 1) & (clean["depth"][..., 0] > 0)
        if region.sum() > 50:
            kept.append((obs["depth"][region] > 0).mean())
            survived = region & (obs["depth"][..., 0] > 0)
            errors.append(obs["depth"][survived] - clean["depth"][survived])
        np.testing.assert_array_equal(obs["depth"][~region], clean["depth"][~region])
        np.testing.assert_array_equal(obs["rgb"], clean["rgb"])
    assert kept and abs(np.mean(kept) - 0.3) < 0.08
    errors = np.concatenate(errors)
    assert abs(errors.mean()) < 0.03 and abs(errors.std() - 0.1) < 0.02


@pytest.mark.parametrize("kwargs, match", [
    ({"confidence_multiplier": 1.2}, "confidence_multiplier"),
    ({"noise_std_m": -0.1}, "noise_std_m"),
])
def test_bad_parameters_are_value_errors(kwargs, match, stub_env):
    with pytest.raises(ValueError, match=match):
        ConfidenceDegradation(stub_env(), **kwargs)
