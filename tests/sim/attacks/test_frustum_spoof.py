"""``FrustumSpoof`` (``frustum_spoof``, white box): depth and LiDAR moved together, within 1 cm of each other."""

import numpy as np
import pytest

from racf.sim.attacks import ATTACKS, FrustumSpoof

SIGN_BEAM = 30  # the stub's LiDAR sees the sign on this beam
SIGN_RGB = (200, 12, 14)  # the stub's sign colour (conftest)


class ShiftRecorder:
    """A defence with room to spare that records the LiDAR shift each question carries."""

    def __init__(self) -> None:
        self.shifts = []

    def would_pass(self, *, depth, speed_mps, dt, yaw_rate_radps=0.0, lidar_shift=0.0) -> bool:
        self.shifts.append(lidar_shift)
        return True


def test_depth_and_lidar_move_together_and_nothing_else_moves(stub_env, drive, grown):
    env = FrustumSpoof(stub_env(), rate_mps=2.0, duration_s=5.0, trigger="always")
    env.attach_defence(ShiftRecorder())
    biases = []
    for obs, clean, info in drive(env, 15):
        sign = info["sign_mask"] & (clean["depth"][..., 0] > 0)
        depth_shift = (obs["depth"][..., 0] - clean["depth"][..., 0])[sign]
        lidar_shift = obs["lidar"][SIGN_BEAM] - clean["lidar"][SIGN_BEAM]
        # The two sensors agree with each other (within 1 cm) and both are off by the bias.
        assert np.abs(depth_shift - lidar_shift).max() <= 0.01
        assert lidar_shift == pytest.approx(env.bias, abs=1e-5)
        others = np.arange(obs["lidar"].size) != SIGN_BEAM
        np.testing.assert_array_equal(obs["lidar"][others], clean["lidar"][others])
        outside = ~grown(info["sign_mask"], 1)  # the sign's region, grown by a pixel, is the attack's
        np.testing.assert_array_equal(obs["depth"][..., 0][outside], clean["depth"][..., 0][outside])
        biases.append(env.bias)
    np.testing.assert_allclose(np.diff(biases), 2.0 * 0.02, atol=1e-9)  # the ramp at its rate
    assert any(s > 0 for s in env.defence.shifts)  # the defence was asked with the LiDAR moved too


def test_registered_as_a_white_box_attack_with_the_ramps_checks(stub_env):
    assert ATTACKS["frustum_spoof"] is FrustumSpoof and FrustumSpoof.threat_model == "white box"
    with pytest.raises(ValueError, match="rate_mps"):
        FrustumSpoof(stub_env(), rate_mps=-1.0)


class SizeShiftRecorder(ShiftRecorder):
    """A defence with a size witness: it takes ``size_shift`` too."""

    def __init__(self) -> None:
        super().__init__()
        self.size_shifts = []

    def would_pass(self, *, depth, speed_mps, dt, yaw_rate_radps=0.0, lidar_shift=0.0, size_shift=0.0) -> bool:
        self.size_shifts.append(size_shift)
        return super().would_pass(depth=depth, speed_mps=speed_mps, dt=dt, lidar_shift=lidar_shift)


def test_scale_box_draws_the_sign_smaller_as_if_at_the_spoofed_distance(stub_env, drive):
    env = FrustumSpoof(stub_env(), rate_mps=2.0, duration_s=5.0, trigger="always", scale_box=True)
    env.attach_defence(SizeShiftRecorder())
    red = np.array(SIGN_RGB)
    shrunk = 0
    for obs, clean, info in drive(env, 30):
        sign = np.all(clean["rgb"] == red, axis=-1)
        if sign.sum() < 30 or env.bias <= 0.2:
            continue
        seen = np.all(np.abs(obs["rgb"].astype(int) - red) < 20, axis=-1)
        factor = info["d_true"] / (info["d_true"] + env.bias)
        assert seen.sum() == pytest.approx(sign.sum() * factor ** 2, rel=0.35)
        shrunk += 1
    assert shrunk and any(s > 0 for s in env.defence.size_shifts)


def test_without_scale_box_the_colour_image_is_untouched_and_no_size_shift_is_asked(stub_env, drive):
    env = FrustumSpoof(stub_env(), rate_mps=2.0, duration_s=5.0, trigger="always")
    env.attach_defence(ShiftRecorder())  # no size_shift keyword: a TypeError if it were passed
    for obs, clean, _ in drive(env, 10):
        np.testing.assert_array_equal(obs["rgb"], clean["rgb"])
    with pytest.raises(ValueError, match="scale_box"):
        FrustumSpoof(stub_env(), scale_box="yes")


def test_scale_box_against_a_defence_without_a_size_witness_asks_it_without_size_shift(stub_env, drive):
    """The EKF's ``would_pass`` takes no ``size_shift``: the attack still scales the image and asks
    it the question it can answer (a TypeError here once stopped a scorecard)."""
    env = FrustumSpoof(stub_env(), rate_mps=2.0, duration_s=5.0, trigger="always", scale_box=True)
    env.attach_defence(ShiftRecorder())
    changed = [not np.array_equal(obs["rgb"], clean["rgb"]) for obs, clean, _ in drive(env, 20)]
    assert any(changed) and any(s > 0 for s in env.defence.shifts)


def test_takes_keyword_reads_the_signature():
    from racf.sim.attacks.stealth_ramp import takes_keyword

    assert takes_keyword(SizeShiftRecorder().would_pass, "size_shift")
    assert not takes_keyword(ShiftRecorder().would_pass, "size_shift")
    assert takes_keyword(lambda **kwargs: True, "size_shift") and not takes_keyword(len, "size_shift")
