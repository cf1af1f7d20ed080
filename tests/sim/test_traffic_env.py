"""Other cars in the env (cross-traffic's world manager): every sensor sees them, a touch is a collision,
they are parked when unused, and they log their own ground truth."""

import gymnasium as gym
import numpy as np
import pytest

from racf import sim
from racf.sim.world.scene import load_model
from racf.sim.world.traffic import TrafficCar
from racf.sim.world.traffic_manager import TrafficManager


@pytest.fixture(scope="module")
def env():
    e = gym.make(sim.ENV_ID, world=(TrafficManager(2),), camera_width=320, camera_height=240)
    yield e
    e.close()


#: Sign 1's approach, 0.5 m before its line: the ego car stands on the straight south along x = -1.984.
SIGN1 = {"sign": 1, "run_up_m": 0.5}


def _parked_ahead(s_m: float = 1.56) -> dict:
    """A red car standing still in the ego car's lane (node 22 south, ``s_m`` along it), about 1.5 m ahead."""
    return {"route": [22, 10], "start_s_m": s_m, "speed_mps": 1.0, "stop_s_m": s_m, "colour": "red"}


def test_the_model_holds_the_other_cars_as_copies_of_the_qcar(env):
    model = load_model(world_xml=TrafficManager(2).scene_xml())
    assert model.nmocap == 2
    ego = {model.geom(i).name for i in range(model.ngeom) if model.geom_bodyid[i] and
           model.body(model.body_rootid[model.geom_bodyid[i]]).name == "qcar"}
    for k in (0, 1):
        names = {model.geom(i).name for i in range(model.ngeom) if model.geom(i).name.startswith(f"traffic_{k}_")}
        assert {n.removeprefix(f"traffic_{k}_") for n in names} == ego


def test_every_sensor_sees_a_car_ahead_and_none_sees_a_parked_one(env):
    obs0, _ = env.reset(seed=0, options={**SIGN1, "cruise_speed": 0.0})
    obs1, info = env.reset(seed=0, options={**SIGN1, "cruise_speed": 0.0, "traffic": [_parked_ahead()]})
    x, y, yaw, speed = info["traffic"][0]
    ego = info["pose"]
    ahead = float(np.hypot(x - ego[0], y - ego[1]))
    assert 1.0 < ahead < 2.0 and speed == 0.0
    # The LiDAR: its scan plane (z = 0.193 m) passes over the other car's body and meets the other
    # car's own LiDAR (a 0.038 m puck on the same mount as ours): a return dead ahead at that range.
    front = np.concatenate([obs1["lidar"][-3:], obs1["lidar"][:4]])
    assert np.nanmin(front) == pytest.approx(ahead - 0.038, abs=0.04)
    assert np.isinf(np.concatenate([obs0["lidar"][-3:], obs0["lidar"][:4]])).all() or \
        np.nanmin(np.concatenate([obs0["lidar"][-3:], obs0["lidar"][:4]])) > ahead + 0.5
    # The depth camera and the colour camera: the image changes where the car stands, and its body is red.
    changed = np.abs(obs1["depth"][..., 0] - obs0["depth"][..., 0]) > 0.05
    assert changed.sum() > 200
    red = (obs1["rgb"][..., 0] > 120) & (obs1["rgb"][..., 1] < 60) & (obs1["rgb"][..., 2] < 60)
    assert (red & changed).sum() > 50
    # With no traffic option, the cars are parked out of sight again.
    obs2, info2 = env.reset(seed=0, options={**SIGN1, "cruise_speed": 0.0})
    assert np.array_equal(obs2["depth"], obs0["depth"]) and info2["traffic"].shape == (0, 4)


def test_driving_into_a_car_is_a_collision_with_it(env):
    env.reset(seed=0, options={**SIGN1, "cruise_speed": 1.0, "traffic": [_parked_ahead()]})
    for _ in range(200):
        _, _, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
        if terminated or truncated:
            break
    assert terminated and info["collision"] and info["collision_with"] == "traffic0"


def test_the_same_seed_gives_the_same_bytes_with_traffic(env):
    car = TrafficCar((7, 14, 16), 0.0, 1.2, 4.0).to_options()
    runs = []
    for _ in range(2):
        obs, _ = env.reset(seed=3, options={"sign": 3, "cruise_speed": 1.0, "traffic": [car, {**car, "colour": "blue",
                                                                                              "depart_t_s": 0.5}]})
        frames = [obs]
        for _ in range(40):
            obs, *_ = env.step(np.array([1.0, 0.0], np.float32))
            frames.append(obs)
        runs.append(frames)
    for a, b in zip(*runs):
        for key in a:
            assert np.array_equal(a[key], b[key]), key


def test_bad_traffic_options_name_the_problem(env):
    with pytest.raises(ValueError, match="holds 2"):
        env.reset(options={"sign": 2, "traffic": [_parked_ahead()] * 3})
    with pytest.raises(ValueError, match="list of other cars"):
        env.reset(options={"sign": 2, "traffic": {"route": [4, 14]}})
    with pytest.raises(ValueError, match=r"cars must be an int in 0\.\.4"):
        TrafficManager(9)
    with pytest.raises(ValueError, match="conflict_xy"):
        env.reset(options={"sign": 2, "traffic": {"cars": [], "conflict_xy": 3.0}})


def test_the_ideal_lidar_sees_another_car_too():
    env = gym.make(sim.ENV_ID, world=(TrafficManager(1),), sensor_profile="ideal", camera_width=160, camera_height=120)
    try:
        obs0, _ = env.reset(seed=0, options={**SIGN1, "cruise_speed": 0.0})
        obs1, info = env.reset(seed=0, options={**SIGN1, "cruise_speed": 0.0, "traffic": [_parked_ahead()]})
    finally:
        env.close()
    x, y = info["traffic"][0][:2]
    ahead = float(np.hypot(x - info["pose"][0], y - info["pose"][1]))
    front = lambda scan: np.concatenate([scan[-3:], scan[:4]])  # noqa: E731
    assert np.nanmin(front(obs1["lidar"])) == pytest.approx(ahead - 0.038, abs=0.04)
    assert np.nanmin(front(obs0["lidar"])) > ahead + 0.5


def test_the_cars_and_the_conflict_point_are_declared_columns_of_the_managers_info(env):
    _, info = env.reset(seed=0, options={**SIGN1, "cruise_speed": 0.0,
                                         "traffic": {"cars": [_parked_ahead()], "conflict_xy": [1.0, 2.0]}})
    manager = env.unwrapped.world[0]
    names = [c.name for c in manager.columns()]
    assert set(names) <= set(info) and len(names) == len(set(names)) == 2 + 4 * 4
    assert (info["conflict_x"], info["conflict_y"]) == (1.0, 2.0)
    assert info["traffic0_x"] == pytest.approx(info["traffic"][0][0]) and np.isnan(info["traffic1_x"])
