"""``StealthRamp`` (``stealth_ramp``, white box): the bias grows at its rate as far as the defence's detector lets it."""

import numpy as np
import pytest

from racf.sim.attacks import ATTACKS, DepthBias, StealthRamp
from racf.sim.attacks.stealth_ramp import quiet_bias


class RoomDefence:
    """A defence whose detector stays quiet for depths up to ``room`` past the truth (the stub's sign)."""

    def __init__(self, env, room: float) -> None:
        self.env, self.room, self.asked = env, room, 0

    def would_pass(self, *, depth, speed_mps, dt, yaw_rate_radps=0.0, lidar_shift=0.0) -> bool:
        self.asked += 1
        return depth <= self.env.unwrapped.sign_distance_m + self.room


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


def test_the_ramp_stays_under_the_defences_threshold_and_uses_its_room(stub_env, drive):
    env = StealthRamp(stub_env(), rate_mps=5.0, margin=0.9, duration_s=5.0, trigger="always")
    env.attach_defence(RoomDefence(env, room=0.25))
    biases = _biases(env, drive, 20)
    assert biases.max() / 0.9 <= 0.25 + 1e-6  # with its reserve, never past the threshold
    assert biases[-1] > 0.9 * 0.25 - 1e-3  # and as far as it may go
    assert env.held_back > 0 and env.defence.asked > 0


def test_a_slow_ramp_grows_at_its_rate_and_a_defence_without_a_detector_leaves_it_uncapped(stub_env, drive):
    slow = StealthRamp(stub_env(), rate_mps=0.5, duration_s=5.0, trigger="always")
    slow.attach_defence(RoomDefence(slow, room=10.0))
    np.testing.assert_allclose(np.diff(_biases(slow, drive)), 0.5 * 0.02, atol=1e-5)
    fast = StealthRamp(stub_env(), rate_mps=20.0, duration_s=5.0, trigger="always")  # raw depth: no defence
    np.testing.assert_allclose(np.diff(_biases(fast, drive)), 20.0 * 0.02, atol=1e-4)


def test_quiet_bias_finds_the_edge_of_the_quiet_set():
    assert quiet_bias(lambda b: b <= 0.3, 0.0, 0.2) == 0.2  # the wanted step is quiet
    assert quiet_bias(lambda b: b <= 0.3, 0.1, 0.5) == pytest.approx(0.3, abs=1e-3)
    assert quiet_bias(lambda b: b <= 0.3, 0.4, 0.5) == 0.4  # already flagged: it does not grow
    assert quiet_bias(lambda b: b >= -0.3, 0.0, -1.0) == pytest.approx(-0.3, abs=1e-3)  # direction -1


def test_against_odca_a_noise_free_ramp_never_opens_the_gate_and_is_held_within_two_tau():
    """ODCA as shipped, an honest LiDAR, a straight approach: the ramp rides the gate's edge
    (the depth may sit tau off the LiDAR, and re-anchor the kinematic branch there)."""
    from racf.controllers import PerceptionSample
    from racf.experiments.car.estimators import make_estimator

    odca = make_estimator("odca")
    odca.reset()
    tau = odca.model.config.gate.tau_m
    d, v, dt, bias = 6.0, 1.5, 0.02, 0.0
    for i in range(200):
        d -= v * dt
        if i >= 50:  # the attack starts once the branch is anchored
            bias = quiet_bias(lambda b: odca.would_pass(depth=d + b, speed_mps=v, dt=dt), bias, bias + 5.0 * dt)
        lidar = (d - odca.model.config.alignment.beta) / odca.model.config.alignment.alpha  # the raw LiDAR of d
        odca.estimate(PerceptionSample(None, d + bias, 0.9, lidar, 0.0), v, dt)
        assert odca.diagnostics()["flag"] == 0.0
    assert tau < bias <= 2 * tau + 1e-3


def test_only_a_white_box_attack_may_read_the_defence(stub_env):
    assert ATTACKS["stealth_ramp"] is StealthRamp and StealthRamp.threat_model == "white box"
    with pytest.raises(ValueError, match="black box"):
        DepthBias(stub_env()).attach_defence(RoomDefence(None, 1.0))


@pytest.mark.parametrize("kwargs,match", [({"rate_mps": -1.0}, "rate_mps"), ({"rate_mps": 50.0}, "rate_mps"),
                                          ({"direction": 0}, "direction"), ({"margin": 0.0}, "margin"),
                                          ({"region": "sky"}, "region")])
def test_bad_parameters_fail_naming_what_is_allowed(kwargs, match, stub_env):
    with pytest.raises(ValueError, match=match):
        StealthRamp(stub_env(), **kwargs)

