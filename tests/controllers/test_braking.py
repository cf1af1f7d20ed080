"""The braking controller on synthetic distance sequences (no simulator)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.controllers import BrakingConfig, Phase, SpeedPI, SpeedProfile, StopSignBraker

DT = 0.02
DEPTH_AT_LINE = 0.12


def _drive(v0: float, start_to_line: float, config: BrakingConfig | None = None, detect=lambda d: True,
           measure=lambda d: d, lag_s: float = 0.0, max_steps: int = 2000):
    """Point-mass car following the braker's speed cap with a first-order lag; returns (braker, final gap, log)."""
    braker = StopSignBraker(config, DEPTH_AT_LINE)
    to_line, v, log = start_to_line, v0, []
    for _ in range(max_steps):
        d = to_line + DEPTH_AT_LINE
        decision = braker.step(detect(d), measure(d), v, DT)
        target = min(v0, decision.speed_cap_mps)
        v += (target - v) * (DT / lag_s if lag_s else 1.0)
        v = max(v, 0.0)
        to_line -= v * DT
        log.append((to_line, v, decision))
        if decision.phase is Phase.DONE:
            break
    return braker, to_line, log


@settings(max_examples=60, deadline=None)
@given(st.floats(0.5, 2.5), st.floats(2.0, 4.0))
def test_a_clean_approach_comes_to_rest_in_the_success_band(v0, start):
    braker, gap, log = _drive(v0, start, lag_s=0.05)
    assert braker.phase is Phase.DONE
    assert 0.0 <= gap <= 0.60


def test_track_needs_k_consecutive_detections():
    config = BrakingConfig(confirm_frames=3)
    braker = StopSignBraker(config, DEPTH_AT_LINE)
    pattern = [True, True, False, True, True, False, True, True, True]
    confirmed = [braker.step(det, 0.3 if det else math.nan, 1.0, DT).confirmed for det in pattern]
    assert confirmed == [False] * 8 + [True]


def test_no_trigger_without_a_confirmed_track_even_when_close():
    braker, gap, log = _drive(1.0, 2.0, detect=lambda d: d > 1.5, measure=lambda d: d if d > 1.5 else math.nan)
    assert not any(dec.brake for _, _, dec in log)
    assert gap < 0  # it ran the line: the sign was lost before the braking point


def test_lost_distance_drops_the_track_but_a_repairing_estimator_keeps_it():
    # Detections stop 1.2 m before the line; raw depth then gives NaN, a repair gives the distance.
    raw_braker, raw_gap, _ = _drive(1.5, 3.0, detect=lambda d: d > 1.3, measure=lambda d: d if d > 1.3 else math.nan)
    rep_braker, rep_gap, _ = _drive(1.5, 3.0, detect=lambda d: d > 1.3)
    assert raw_gap < 0
    assert 0.0 <= rep_gap <= 0.60


def test_trigger_distance_grows_with_speed_and_a_late_trigger_brakes_harder():
    def trigger_gap(v0):
        _, _, log = _drive(v0, 3.0)
        return next(gap for gap, _, dec in log if dec.brake)
    assert trigger_gap(1.0) < trigger_gap(1.5) < trigger_gap(2.0)
    # Detections only from 0.6 m before the line at 2 m/s: it still stops, with a steeper cap.
    _, gap, log = _drive(2.0, 1.5, detect=lambda d: d < 0.72)
    speeds = [v for _, v, dec in log if dec.brake]
    assert 0.0 <= gap <= 0.60
    assert max(a - b for a, b in zip(speeds, speeds[1:])) / DT > 2 * BrakingConfig().decel_mps2


def test_dwell_then_done_and_the_cap_is_lifted():
    config = BrakingConfig(dwell_s=0.5)
    braker, _, log = _drive(1.0, 2.0, config)
    phases = [dec.phase for _, _, dec in log]
    stopped = [i for i, p in enumerate(phases) if p is Phase.STOPPED]
    assert len(stopped) == pytest.approx(0.5 / DT, abs=1)
    assert phases[-1] is Phase.DONE and math.isinf(log[-1][2].speed_cap_mps)


def test_bad_config_and_dt():
    with pytest.raises(ValueError, match="confirm_frames"):
        BrakingConfig(confirm_frames=0)
    with pytest.raises(ValueError, match="decel_mps2"):
        BrakingConfig(decel_mps2=-1.0)
    with pytest.raises(ValueError, match="dt"):
        StopSignBraker().step(True, 1.0, 1.0, 0.0)


def test_speed_profile_slows_before_and_through_curves():
    s = np.linspace(0, 4, 401)
    kappa = np.where((s > 2) & (s < 3), 1.6, 0.0)
    profile = SpeedProfile(s, kappa, max_lateral_accel_mps2=3.0, max_decel_mps2=2.0)
    assert profile.at(2.5, 2.0) == pytest.approx(math.sqrt(3.0 / 1.6), rel=1e-6)
    assert profile.at(0.5, 2.0) == 2.0
    before = profile.at(1.9, 2.0)
    assert math.sqrt(3.0 / 1.6) < before < 2.0


def test_speed_pi_removes_a_steady_error_and_never_reverses():
    pi = SpeedPI()
    v = 0.0
    for _ in range(500):
        cmd = pi.command(1.0, v, DT)
        v = 0.9 * cmd  # a plant that only reaches 90 % of the command
    assert v == pytest.approx(1.0, abs=0.01)
    assert pi.command(0.0, 1.0, DT) == 0.0
    assert pi.command(0.5, 2.0, DT) >= 0.0


def test_a_wheel_locked_at_the_trigger_does_not_make_the_stop_creep():
    """Another stage's hard brake locks the wheels just before the trigger: the encoder reads 0.1 m/s
    while the body, at 1.5 m/s a step before, can have lost no more than the grip (0.75 g) in 20 ms.
    The braker plans on that bound, so its first cap is 1.5 - 0.75 * 9.81 * 0.02 = 1.35285 m/s, not the
    locked wheel's 0.1 m/s (on which it crept to the stop point for 4 s)."""
    braker = StopSignBraker(BrakingConfig(), DEPTH_AT_LINE)
    for _ in range(5):  # confirmed, far from the trigger (2.58 m left to the stop point)
        assert braker.step(True, 3.0, 1.5, DT).phase is Phase.CRUISE
    # 0.82 m: 0.40 m to the stop point (0.82 - 0.12 - 0.30), inside the 0.45 m floor.
    decision = braker.step(True, 0.82, 0.1, DT)
    assert decision.phase is Phase.BRAKING
    assert decision.speed_cap_mps == pytest.approx(1.35285, abs=1e-6)
