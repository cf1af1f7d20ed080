"""``TimedDropout`` (``dropout_timed``): the depth attack starts after k empty scans and stops when the LiDAR sees the sign."""

import numpy as np
import pytest

from racf.sim.attacks import ATTACKS, LidarDropout, TimedDropout

SIGN_BEAM = 30  # the stub's LiDAR sees the sign on this beam


def _silenced(stub_env, steps_silent):
    """The stub with the sign's LiDAR returns removed for the first ``steps_silent`` steps."""
    return LidarDropout(stub_env(), share=1.0, sector="sign", duration_s=steps_silent / 50, cooldown_s=30.0,
                        trigger="always")


@pytest.mark.parametrize("k", [1, 3, 6])
def test_it_starts_only_after_k_empty_scans_and_stops_when_the_sign_returns(k, stub_env, drive):
    env = TimedDropout(_silenced(stub_env, 12), scans=k)
    rows = list(drive(env, 20))
    on = ["dropout_timed" in info["attack"] for _, _, info in rows]
    # The stub delivers a scan every step; the first k - 1 silent scans do not start it.
    silent = [not np.isfinite(obs["lidar"][SIGN_BEAM]) for obs, _, _ in rows]
    assert silent[:12] == [True] * 12 and not any(silent[12:])
    assert on == [k - 1 <= step < 12 for step in range(20)]
    for (obs, clean, info), active in zip(rows, on):
        sign = info["sign_mask"] & (clean["depth"][..., 0] > 0)
        if active:
            assert (obs["depth"][..., 0][sign] == 0).all()  # blackout on the sign
        else:
            np.testing.assert_array_equal(obs["depth"], clean["depth"])
    assert env.schedule.windows == [(rows[k - 1][2]["time"], rows[11][2]["time"])]


def test_a_lidar_that_sees_the_sign_is_never_attacked_and_the_bias_effect_adds_its_offset(stub_env, drive):
    env = TimedDropout(stub_env(), scans=1)
    assert not any(info["attack_active"] for _, _, info in drive(env, 20))
    env = TimedDropout(_silenced(stub_env, 10), scans=2, effect="bias", bias_m=0.5)
    for obs, clean, info in drive(env, 6):
        sign = info["sign_mask"] & (clean["depth"][..., 0] > 0)
        if "dropout_timed" in info["attack"]:
            np.testing.assert_allclose(obs["depth"][..., 0][sign], clean["depth"][..., 0][sign] + 0.5)


def test_registered_and_bad_parameters_fail_naming_what_is_allowed(stub_env):
    assert ATTACKS["dropout_timed"] is TimedDropout
    for kwargs, match in (({"scans": 0}, "scans"), ({"scans": 1.5}, "scans"), ({"effect": "patch"}, "effect"),
                          ({"bias_m": -1.0}, "bias_m")):
        with pytest.raises(ValueError, match=match):
            TimedDropout(stub_env(), **kwargs)
