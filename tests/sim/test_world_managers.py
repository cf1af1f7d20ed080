"""World managers: the env runs a scenario's bodies without knowing them. Managers that build the
same world are equal (an env is reused), a manager's reset option is accepted only when the env
holds it, and two parts may not read the same option."""

import gymnasium as gym
import numpy as np
import pytest

import racf.sim as sim
from racf.sim.env.config import EnvConfig
from racf.sim.env.world import TruthColumn, WorldManager
from racf.sim.world.traffic_manager import TrafficManager


class _Marker(WorldManager):
    """A box placed at the reset option ``marker``'s (x, y), or below the floor without it."""

    name = option = "marker"

    def __init__(self, size_m: float = 0.1) -> None:
        self.size_m = size_m

    def key(self) -> tuple:
        return (self.size_m,)

    def scene_xml(self) -> str:
        return (f'<body name="marker" mocap="true" pos="0 0 -5"><geom name="marker" type="box" '
                f'size="{self.size_m} {self.size_m} {self.size_m}"/></body>')

    def bind(self, model) -> None:
        self._mocap = int(model.body_mocapid[model.body("marker").id])

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        if value is not None:
            data.mocap_pos[self._mocap] = (*value, 0.05)

    def info(self, substep: int) -> dict:
        return {"marker_placed": True}


def test_managers_that_build_the_same_world_are_equal():
    assert _Marker(0.1) == _Marker(0.1) and hash(_Marker(0.1)) == hash(_Marker(0.1))
    assert _Marker(0.1) != _Marker(0.2) and TrafficManager(1) != TrafficManager(2)


def test_the_env_places_a_managers_body_and_reports_it_in_info_only():
    env = gym.make(sim.ENV_ID, world=(_Marker(),), camera_width=160, camera_height=120)
    try:
        obs, info = env.reset(seed=0, options={"sign": 2, "cruise_speed": 1.0, "marker": (1.0, 2.0)})
        base = env.unwrapped
        assert np.allclose(base.data.mocap_pos[base.world[0]._mocap][:2], (1.0, 2.0))
        assert info["marker_placed"] and "marker_placed" not in obs
        with pytest.raises(ValueError, match="unknown reset option"):
            gym.make(sim.ENV_ID, camera_width=160, camera_height=120).reset(options={"marker": (0, 0)})
    finally:
        env.close()


def test_two_parts_may_not_read_the_same_reset_option():
    with pytest.raises(ValueError, match=r"reset option\(s\) \['marker'\]"):
        EnvConfig(world=(_Marker(0.1), _Marker(0.2)))
    with pytest.raises(ValueError, match=r"reset option\(s\) \['traffic'\]"):
        EnvConfig(world=(TrafficManager(1), TrafficManager(2)))


def test_two_managers_may_not_log_the_same_column():
    class _Twin(_Marker):
        option = "twin"

        def columns(self):
            return (TruthColumn("marker_placed", "bool", "placed"),)

    class _Placed(_Marker):
        def columns(self):
            return (TruthColumn("marker_placed", "bool", "placed"),)

    with pytest.raises(ValueError, match=r"log column\(s\) \['marker_placed'\]"):
        EnvConfig(world=(_Placed(), _Twin()))
