"""The pose filter: accuracy on simulated drives against the truth, heading wrap, gating,
bad inputs, and a covariance that stays symmetric PSD whatever the call sequence."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from racf.controllers.localisation import PoseFilter, PoseFilterConfig, wrap_angle

RATE_HZ, FIX_EVERY = 50, 5  # control at 50 Hz, fixes at 10 Hz
BIAS = math.radians(0.4)  # constant gyro zero-rate offset, rad/s
GYRO_SAMPLE_STD = math.radians(0.0038) * math.sqrt(RATE_HZ)  # datasheet density at 50 Hz
DRIFT_AMP_M, DRIFT_PERIOD_S = 0.03, 30.0
SKIP = RATE_HZ  # the first second (the bias is still unknown) is left out of the scores


def _yaw_rate(path, t, v, state):
    """Yaw rate of the truth: a 1 m circle, or a figure of eight (full left, full right circles)."""
    if path == "circle":
        return v
    if path == "eight":
        return state["sign"] * v
    if path == "west":  # a slalom about yaw = pi, so the heading crosses +-pi every second
        return 0.6 * math.cos(2 * math.pi * t / 2.0)
    raise AssertionError(path)


def drive(path, seed, *, fixes=True, config=None, yaw0=0.0, seconds=60.0, speed_scale=1.02):
    """Drives the truth with exact arcs and runs the filter on noisy encoder, gyro and fixes.

    The encoder reads 2 % long (tyre radius) with 2 % white slip; the fix is the truth plus a
    30 s sine drift of 3 cm per axis (x and y out of phase) plus 1 cm / 0.01 rad white noise.
    Returns (estimates (N, 3), truth (N, 3), drift (N, 2), bias estimates (N,), filter).
    """
    rng = np.random.default_rng(seed)
    dt = 1.0 / RATE_HZ
    phase_x = rng.uniform(0, 2 * math.pi)
    phase_y = phase_x + 1.3

    def drift(t):
        w = 2 * math.pi * t / DRIFT_PERIOD_S
        return DRIFT_AMP_M * math.sin(w + phase_x), DRIFT_AMP_M * math.sin(w + phase_y)

    def fix(t, x, y, yaw):
        dx, dy = drift(t)
        return [x + dx + rng.normal(0, 0.01), y + dy + rng.normal(0, 0.01), wrap_angle(yaw + rng.normal(0, 0.01))]

    x, y, yaw, state, turned = 0.0, 0.0, yaw0, {"sign": 1.0}, 0.0
    f = PoseFilter(config)
    f.reset(fix(0.0, x, y, yaw))
    est, truth, drifts, biases = [], [], [], []
    for k in range(1, int(round(seconds * RATE_HZ)) + 1):
        t = k * dt
        v = 1.5 + 0.5 * math.sin(2 * math.pi * t / 17.0)  # 1-2 m/s
        w = _yaw_rate(path, t, v, state)
        dth = w * dt
        if abs(dth) > 1e-12:
            x += v / w * (math.sin(yaw + dth) - math.sin(yaw))
            y -= v / w * (math.cos(yaw + dth) - math.cos(yaw))
        else:
            x += v * dt * math.cos(yaw)
            y += v * dt * math.sin(yaw)
        yaw = wrap_angle(yaw + dth)
        turned += abs(dth)
        if turned >= 2 * math.pi:
            turned -= 2 * math.pi
            state["sign"] = -state["sign"]
        f.predict(v * speed_scale * (1 + rng.normal(0, 0.02)), w + BIAS + rng.normal(0, GYRO_SAMPLE_STD), dt)
        if fixes and k % FIX_EVERY == 0:
            f.correct(fix(t, x, y, yaw))
        est.append(f.pose)
        truth.append((x, y, yaw))
        drifts.append(drift(t))
        biases.append(f.gyro_bias)
    return np.array(est), np.array(truth), np.array(drifts), np.array(biases), f


def scores(est, truth, drifts):
    """(position RMSE, the drift's own RMSE, heading RMSE in degrees), after the first second."""
    e, tr, d = est[SKIP:], truth[SKIP:], drifts[SKIP:]
    pos = math.sqrt(np.mean(np.sum((e[:, :2] - tr[:, :2]) ** 2, axis=1)))
    drift = math.sqrt(np.mean(np.sum(d ** 2, axis=1)))
    heading_err = np.array([wrap_angle(a) for a in e[:, 2] - tr[:, 2]])
    return pos, drift, math.degrees(math.sqrt(np.mean(heading_err ** 2)))


@pytest.mark.parametrize("path, seed", [("circle", 1), ("eight", 2)])
def test_fusion_tracks_the_truth_to_the_fix_drift_and_learns_the_gyro_bias(path, seed):
    est, truth, drifts, biases, _ = drive(path, seed)
    pos, drift, heading_deg = scores(est, truth, drifts)
    # The drift is too slow to tell from motion; the filter must remove the rest (white noise).
    assert pos <= drift + 0.01, (pos, drift)
    assert heading_deg < 1.0
    bias_err = np.abs(biases[-20 * RATE_HZ:] - BIAS)  # the last 20 s
    assert math.degrees(bias_err.max()) < 0.1


def test_dead_reckoning_alone_drifts_in_heading():
    # Without fixes the 0.4 deg/s bias is never learnt: the heading check above would fail.
    est, truth, drifts, biases, _ = drive("circle", 1, fixes=False)
    _, _, heading_deg = scores(est, truth, drifts)
    assert heading_deg > 5.0
    assert biases[-1] == 0.0


def test_heading_across_plus_minus_pi():
    est, truth, drifts, _, _ = drive("west", 3, yaw0=math.pi, seconds=20.0)
    assert np.any(truth[:, 2] > 3.0) and np.any(truth[:, 2] < -3.0)  # the truth does cross
    pos, drift, heading_deg = scores(est, truth, drifts)
    assert heading_deg < 1.0 and pos <= drift + 0.01
    assert np.all(est[:, 2] > -math.pi) and np.all(est[:, 2] <= math.pi)


def test_a_fix_just_across_pi_pulls_the_short_way():
    f = PoseFilter()
    f.reset([0.0, 0.0, 3.10])
    f.correct([0.0, 0.0, -3.10])  # 0.083 rad away across pi, not 6.2 rad
    assert abs(wrap_angle(f.pose[2] - math.pi)) < 0.05
    assert wrap_angle(-math.pi) == math.pi and wrap_angle(math.pi) == math.pi


def test_equal_noise_at_rest_fuses_to_the_mean():
    cfg = PoseFilterConfig(fix_std_m=0.05, fix_std_yaw_rad=0.02)
    f = PoseFilter(cfg)
    f.reset([1.0, 2.0, 0.5])
    f.correct([1.1, 2.0, 0.5])
    assert f.pose == pytest.approx([1.05, 2.0, 0.5])
    assert f.covariance[0, 0] == pytest.approx(0.05 ** 2 / 2)


def test_noiseless_prediction_is_the_unicycle_model_and_dt_zero_is_a_no_op():
    f = PoseFilter(PoseFilterConfig(speed_std_mps=0.0, gyro_std_radps=0.0, bias_walk_radps=0.0))
    f.reset([0.0, 0.0, 0.0])
    f.predict(2.0, 0.0, 0.5)
    assert f.pose == pytest.approx([1.0, 0.0, 0.0])
    f.predict(1.0, 1.0, 0.0)
    assert f.pose == pytest.approx([1.0, 0.0, 0.0])
    f.predict(1.0, math.pi, 0.5)  # midpoint heading pi/4, yaw ends at pi/2
    assert f.pose == pytest.approx([1.0 + 0.5 * math.cos(math.pi / 4), 0.5 * math.sin(math.pi / 4), math.pi / 2])
    assert f.pose is not f.pose and f.covariance is not f.covariance  # copies


def test_gate_rejects_a_far_fix_keeps_near_ones_and_recovers_when_lost():
    gated = PoseFilter(PoseFilterConfig(gate_sigma=5.0, gate_reset_after=3))
    free = PoseFilter()
    for f in (gated, free):
        f.reset([0.0, 0.0, 0.0])
        for _ in range(20):
            f.correct([0.0, 0.0, 0.0])
    before = gated.pose
    gated.correct([1.0, 0.0, 0.0])
    free.correct([1.0, 0.0, 0.0])
    np.testing.assert_array_equal(gated.pose, before)
    assert gated.rejected_fixes == 1 and free.pose[0] > 0.04  # 1/22 of the way: 21 fixes at rest
    gated.correct([0.01, 0.0, 0.0])  # a plausible fix is fused and clears the run of rejections
    assert 0.0 < gated.pose[0] < 0.01 and gated.rejected_fixes == 1
    for _ in range(4):  # 3 rejected in a row, then the 4th restarts the filter at the localiser
        gated.correct([1.0, 0.0, 0.0])
    assert gated.pose == pytest.approx([1.0, 0.0, 0.0]) and gated.rejected_fixes == 4


def test_gate_does_not_reject_the_localisers_ordinary_fixes():
    *_, f = drive("eight", 4, config=PoseFilterConfig(gate_sigma=5.0))
    assert f.rejected_fixes == 0


@pytest.mark.parametrize("field, value", [
    ("fix_std_m", 0.0), ("fix_std_m", math.nan), ("fix_std_yaw_rad", -0.1), ("speed_std_mps", -1.0),
    ("gyro_std_radps", math.inf), ("bias_walk_radps", -1e-4), ("init_bias_std_radps", 0.0),
    ("gate_sigma", 0.0), ("gate_sigma", math.nan), ("gate_reset_after", 0), ("gate_reset_after", 2.5),
])
def test_bad_config_names_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        PoseFilterConfig(**{field: value})


def test_optional_gate_values_are_accepted():
    PoseFilterConfig(gate_sigma=None)
    PoseFilterConfig(gate_sigma=math.inf)
    PoseFilterConfig(speed_std_mps=0.0, gyro_std_radps=0.0, bias_walk_radps=0.0)


def test_calls_before_reset_and_bad_inputs_raise():
    f = PoseFilter()
    assert not f.initialised
    with pytest.raises(RuntimeError, match=r"reset\(fix\) first"):
        f.predict(1.0, 0.0, 0.02)
    with pytest.raises(RuntimeError, match=r"reset\(fix\) first"):
        f.correct([0.0, 0.0, 0.0])
    f.reset([0.0, 0.0, 0.0])
    assert f.initialised
    with pytest.raises(ValueError, match="dt"):
        f.predict(1.0, 0.0, -0.01)
    with pytest.raises(ValueError, match="speed"):
        f.predict(math.nan, 0.0, 0.02)
    with pytest.raises(ValueError, match="yaw_rate"):
        f.predict(1.0, math.inf, 0.02)
    with pytest.raises(ValueError, match="fix"):
        f.correct([0.0, 0.0])
    with pytest.raises(ValueError, match="fix"):
        f.reset([0.0, math.nan, 0.0])


_predict = st.tuples(st.just("p"), st.floats(-3, 3), st.floats(-4, 4), st.floats(0, 0.2))
_correct = st.tuples(st.just("c"), st.floats(-10, 10), st.floats(-10, 10), st.floats(-4, 4))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.one_of(_predict, _correct), min_size=1, max_size=60), st.sampled_from([None, 3.0]))
def test_covariance_stays_symmetric_psd(ops, gate):
    f = PoseFilter(PoseFilterConfig(gate_sigma=gate))
    f.reset([0.0, 0.0, 0.0])
    for op, a, b, c in ops:
        if op == "p":
            f.predict(a, b, c)
        else:
            f.correct([a, b, c])
        P = f.covariance
        assert np.all(np.isfinite(P)) and np.all(np.isfinite(f.pose))
        np.testing.assert_array_equal(P, P.T)
        assert np.linalg.eigvalsh(P).min() >= -1e-12 * max(1.0, np.abs(P).max())
        assert -math.pi < f.pose[2] <= math.pi


def test_the_body_origins_sideways_motion_in_a_turn_is_followed():
    """A car-like body slips no sideways at its rear axle, so its origin (0.128 m ahead) moves
    sideways at w x 0.128 in a turn. Told that, dead reckoning follows a circle; without it the
    estimate leaves the circle by centimetres within a second."""
    dt, v, w, lever = 0.02, 1.5, 1.5, 0.128
    x = y = yaw = 0.0
    told, untold = PoseFilter(), PoseFilter()
    for f in (told, untold):
        f.reset([0.0, 0.0, 0.0])
    for _ in range(50):  # 1 s of a 1 m circle of the rear axle
        mid = yaw + 0.5 * w * dt
        vx, vy = v * math.cos(mid) - w * lever * math.sin(mid), v * math.sin(mid) + w * lever * math.cos(mid)
        x, y, yaw = x + vx * dt, y + vy * dt, yaw + w * dt
        told.predict(v, w, dt, lateral_speed=w * lever)
        untold.predict(v, w, dt)
    assert np.hypot(told.pose[0] - x, told.pose[1] - y) < 0.005
    assert np.hypot(untold.pose[0] - x, untold.pose[1] - y) > 0.1
