"""QCar 2 vehicle model: geometry from the facts, speed tracking, turning radius, braking, servo lag.

Uses the compiled map model and ``QCar2`` directly (no env). Control at 50 Hz: apply the
command, then 10 physics steps of 2 ms.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from racf.sim.vehicle import QCar2, VehicleConfig
from racf.sim.world import map_facts
from racf.sim.world.scene import load_model

WHEELBASE_M = 0.256
TRACK_M = 0.170
WHEEL_RADIUS_M = 0.033
CONTROL_DT_S = 0.02

# A free straight: x = -1.9 runs north from y = -1.0 to the north wall (y = 4.72) with no
# prop within 0.35 m (stop signs 0 and 1 stand at x = -1.5; the west wall is at x = -2.27).
STRAIGHT_X, STRAIGHT_Y0, NORTH = -1.9, -1.0, math.pi / 2
# An open patch of floor: no prop or wall within 1.0 m of this point.
OPEN_CENTRE = (-0.7, 3.0)


@pytest.fixture(scope="module")
def sim_car():
    model = load_model()
    data = mujoco.MjData(model)
    return model, data, QCar2(model)


def _drive(sim_car, pose, v0, speed_cmd, steer_cmd, duration_s, steer0=0.0):
    """Places the car and drives a constant command; returns the state after each control step."""
    model, data, car = sim_car
    mujoco.mj_resetData(model, data)
    car.place(data, *pose, speed=v0, steer=steer0)
    mujoco.mj_forward(model, data)
    states = []
    for _ in range(int(round(duration_s / CONTROL_DT_S))):
        car.apply(data, speed_cmd, steer_cmd)
        mujoco.mj_step(model, data, nstep=10)
        states.append(car.state(data))
    return states


def test_open_patch_is_free_of_props():
    props = [p[:2] for p in map_facts.STOP_SIGNS + map_facts.TRAFFIC_LIGHTS + map_facts.YIELD_SIGNS]
    for p in props:
        assert math.dist(p, OPEN_CENTRE) > 0.9
        assert abs(p[0] - STRAIGHT_X) > 0.3 or p[1] < STRAIGHT_Y0
    x0, x1, y0, y1 = map_facts.WALL_BOUNDS_M
    assert min(OPEN_CENTRE[0] - x0, x1 - OPEN_CENTRE[0], OPEN_CENTRE[1] - y0, y1 - OPEN_CENTRE[1]) > 0.9


def test_geometry_matches_facts(sim_car):
    model, _, car = sim_car
    assert car.wheelbase_m == pytest.approx(WHEELBASE_M, abs=1e-3)
    assert car.track_m == pytest.approx(TRACK_M, abs=1e-3)
    assert car.wheel_radius_m == pytest.approx(WHEEL_RADIUS_M, abs=1e-4)

    # Independently from the model's body positions (wheel centres in the car body frame).
    fl = model.body("knuckle_fl").pos
    fr = model.body("knuckle_fr").pos
    rl = model.body("wheel_rl").pos
    rr = model.body("wheel_rr").pos
    assert fl[0] - rl[0] == pytest.approx(WHEELBASE_M, abs=1e-3)
    assert fr[0] - rr[0] == pytest.approx(WHEELBASE_M, abs=1e-3)
    assert fl[1] - fr[1] == pytest.approx(TRACK_M, abs=1e-3)
    assert rl[1] - rr[1] == pytest.approx(TRACK_M, abs=1e-3)
    # Body origin midway between the axles; axles at wheel-radius height (wheels on the ground).
    assert fl[0] + rl[0] == pytest.approx(0.0, abs=1e-3)
    for p in (fl, fr, rl, rr):
        assert p[2] == pytest.approx(WHEEL_RADIUS_M, abs=1e-3)
    for name in ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"):
        assert model.geom(name).size[0] == pytest.approx(WHEEL_RADIUS_M, abs=1e-4)


def test_wheels_touch_the_floor_after_settling(sim_car):
    model, data, car = sim_car
    states = _drive(sim_car, (STRAIGHT_X, STRAIGHT_Y0, NORTH), 0.0, 0.0, 0.0, 0.5)
    body_z = data.xpos[car.body_id][2]
    assert abs(body_z) < 5e-3
    assert abs(states[-1].speed) < 0.01


@pytest.mark.parametrize("speed", [1.0, 1.5])
def test_steady_speed_within_5_percent(sim_car, speed):
    states = _drive(sim_car, (STRAIGHT_X, STRAIGHT_Y0, NORTH), 0.0, speed, 0.0, 2.0)
    final = states[-1]
    assert final.speed == pytest.approx(speed, rel=0.05)
    # Settled, not passing through: the last half second stays within 5 % as well.
    for s in states[-25:]:
        assert s.speed == pytest.approx(speed, rel=0.05)
    # Drove straight north along the free lane.
    assert abs(final.x - STRAIGHT_X) < 0.1
    assert final.y - STRAIGHT_Y0 == pytest.approx(speed * 2.0, rel=0.2)
    assert abs(final.yaw - NORTH) < math.radians(3)


def test_full_lock_turning_radius(sim_car):
    _, _, car = sim_car
    lock = math.radians(30.0)
    expected = WHEELBASE_M / math.tan(lock)  # 0.443 m, rear-axle midpoint
    cx, cy = OPEN_CENTRE
    # Heading east with the turn centre (to the left) at OPEN_CENTRE.
    pose = (cx + WHEELBASE_M / 2, cy - expected, 0.0)
    states = _drive(sim_car, pose, 0.5, 0.5, lock, 6.0, steer0=lock)
    settled = states[50:]  # drop the first second
    rear = np.array([[s.x - 0.5 * car.wheelbase_m * math.cos(s.yaw),
                      s.y - 0.5 * car.wheelbase_m * math.sin(s.yaw)] for s in settled])
    # Algebraic (Kasa) circle fit.
    a = np.column_stack([2 * rear, np.ones(len(rear))])
    b = (rear**2).sum(axis=1)
    (ux, uy, c), *_ = np.linalg.lstsq(a, b, rcond=None)
    radius = math.sqrt(c + ux**2 + uy**2)
    assert radius == pytest.approx(expected, rel=0.10)
    # It really went round (left): most of a turn of heading in the settled part.
    yaw_rates = np.array([s.yaw_rate for s in settled])
    assert (yaw_rates > 0).all()
    assert yaw_rates.sum() * CONTROL_DT_S > 1.4 * math.pi
    # The points lie on a circle (small residual), not a spiral.
    residual = np.abs(np.hypot(rear[:, 0] - ux, rear[:, 1] - uy) - radius)
    assert residual.max() < 0.05


def test_braking_is_friction_limited(sim_car):
    v0 = 2.0
    states = _drive(sim_car, (STRAIGHT_X, STRAIGHT_Y0, NORTH), v0, 0.0, 0.0, 2.0)
    speeds = np.array([s.speed for s in states])
    stopped = np.nonzero(np.abs(speeds) < 0.02)[0]
    assert stopped.size, f"never stopped: {speeds[::10]}"
    t_stop = (stopped[0] + 1) * CONTROL_DT_S
    decel = v0 / t_stop
    assert 3.0 <= decel <= 9.0, f"mean deceleration {decel:.2f} m/s^2"
    # Stays stopped.
    assert np.abs(speeds[stopped[0]:]).max() < 0.05
    # Stopping distance consistent with the deceleration.
    dist = states[-1].y - STRAIGHT_Y0
    assert v0**2 / (2 * 9.0) <= dist <= v0**2 / (2 * 3.0)


@pytest.mark.parametrize("v0", [0.0, 0.5])
def test_steering_first_order_lag(sim_car, v0):
    target = 0.3
    states = _drive(sim_car, (STRAIGHT_X, STRAIGHT_Y0, NORTH), v0, v0, target, 1.0)
    at_tau = states[int(round(0.16 / CONTROL_DT_S)) - 1].steering  # after 0.16 s
    assert 0.40 * target <= at_tau <= 0.85 * target
    assert states[-1].steering == pytest.approx(target, rel=0.05)
    # Monotone rise, no overshoot beyond 5 %.
    steer = np.array([s.steering for s in states])
    assert steer.max() <= 1.05 * target
    assert (np.diff(steer[:25]) > -1e-3).all()


def test_steering_command_is_clipped_to_lock(sim_car):
    states = _drive(sim_car, (STRAIGHT_X, STRAIGHT_Y0, NORTH), 0.3, 0.3, 1.0, 1.5)
    assert states[-1].steering == pytest.approx(math.radians(30.0), rel=0.05)


def test_ackermann_inner_wheel_turns_more(sim_car):
    _, _, car = sim_car
    left, right = car.ackermann(math.radians(20))
    assert left > math.radians(20) > right > 0
    # Both wheels point at the same turn centre on the rear axle line.
    r = WHEELBASE_M / math.tan(math.radians(20))
    assert math.tan(left) == pytest.approx(WHEELBASE_M / (r - TRACK_M / 2), rel=1e-6)
    assert math.tan(right) == pytest.approx(WHEELBASE_M / (r + TRACK_M / 2), rel=1e-6)
    assert car.ackermann(-math.radians(20)) == pytest.approx((-right, -left))


def test_vehicle_config_rejects_out_of_range():
    with pytest.raises(ValueError, match="max_speed_mps"):
        VehicleConfig(max_speed_mps=5.0)
    with pytest.raises(ValueError, match="max_steer_rad"):
        VehicleConfig(max_steer_rad=1.0)
