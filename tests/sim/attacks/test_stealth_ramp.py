"""``StealthRamp`` (``stealth_ramp``, white box): the bias grows at its rate, capped per step under the defence's tolerance."""

from types import SimpleNamespace

import numpy as np
import pytest

from sim.attacks import ATTACKS, DepthBias, StealthRamp
from sim.attacks.stealth_ramp import per_step_tolerance

#: A defence as the ramp reads it: ODCA's estimator exposes ``model.config.step_bound_m``.
ODCA_LIKE = SimpleNamespace(model=SimpleNamespace(config=SimpleNamespace(step_bound_m=0.2)))


def _biases(env, drive, steps=12):
    """The bias on the sign's depth pixels each attacked step (obs - clean, where the sign has depth)."""
    out = []
    for obs, clean, info in drive(env, steps):
        sign = info["sign_mask"] & (clean["depth"][..., 0] > 0)
        if info["attack_active"]:
            diff = (obs["depth"][..., 0] - clean["depth"][..., 0])[sign]
            assert np.allclose(diff, diff[0], atol=1e-5)  # one bias over the sign
            out.append(float(diff[0]))
    return np.array(out)


def test_against_odca_each_step_stays_under_its_tolerance(stub_env, drive):
    env = StealthRamp(stub_env(), rate_mps=20.0, margin=0.9, duration_s=5.0, trigger="always")
    env.attach_defence(ODCA_LIKE)
    assert env.max_step_m == pytest.approx(0.18)
    steps = np.diff(np.r_[0.0, _biases(env, drive)])
    assert (steps <= 0.18 + 1e-5).all() and steps[1:].min() > 0.17  # as fast as it may, no faster


def test_a_slow_ramp_grows_at_its_rate_and_a_defence_without_a_test_leaves_it_uncapped(stub_env, drive):
    slow = StealthRamp(stub_env(), rate_mps=0.5, duration_s=5.0, trigger="always")
    slow.attach_defence(ODCA_LIKE)
    np.testing.assert_allclose(np.diff(_biases(slow, drive)), 0.5 * 0.02, atol=1e-5)
    fast = StealthRamp(stub_env(), rate_mps=20.0, duration_s=5.0, trigger="always")  # raw depth: no defence
    assert per_step_tolerance(None) == float("inf")
    np.testing.assert_allclose(np.diff(_biases(fast, drive)), 20.0 * 0.02, atol=1e-4)


def test_only_a_white_box_attack_may_read_the_defence(stub_env):
    assert ATTACKS["stealth_ramp"] is StealthRamp and StealthRamp.threat_model == "white box"
    with pytest.raises(ValueError, match="black box"):
        DepthBias(stub_env()).attach_defence(ODCA_LIKE)


@pytest.mark.parametrize("kwargs,match", [({"rate_mps": -1.0}, "rate_mps"), ({"rate_mps": 50.0}, "rate_mps"),
                                          ({"direction": 0}, "direction"), ({"margin": 0.0}, "margin"),
                                          ({"region": "sky"}, "region")])
def test_bad_parameters_fail_naming_what_is_allowed(kwargs, match, stub_env):
    with pytest.raises(ValueError, match=match):
        StealthRamp(stub_env(), **kwargs)
