"""The stale map's props (racf.sim.env.sign_props): a mapped sign taken away, a phantom put up."""

import gymnasium as gym
import numpy as np
import pytest

from racf import sim
from racf.sim.env.sign_props import PHANTOM_BODY, SignPropsManager
from racf.sim.world.stop_signs import stop_signs


@pytest.fixture(scope="module")
def env():
    env = gym.make(sim.ENV_ID, world=(SignPropsManager(),), camera_width=160, camera_height=120)
    yield env.unwrapped
    env.close()


def test_a_removed_sign_goes_out_of_sight_and_comes_back_at_the_next_reset(env):
    _, info = env.reset(seed=0, options={"sign": 2, "sign_props": {"remove": 2, "phantom": None}})
    assert env.data.body("stop_sign_2").xpos[2] < -4 and info["sign_removed"] == 2 and info["phantom_at"] == -1
    assert not info["sign_in_view"] or not info["sign_mask"].any()
    _, info = env.reset(seed=0, options={"sign": 2})
    assert env.data.body("stop_sign_2").xpos[2] == 0.0 and info["sign_removed"] == -1
    assert env.data.body(PHANTOM_BODY).xpos[2] < -4


def test_a_phantom_stands_where_the_sign_stood_with_no_pole(env):
    _, info = env.reset(seed=0, options={"sign": 1, "sign_props": {"remove": 1, "phantom": 1}})
    sign = stop_signs()[1]
    # Half a plate (5 cm) out from the pole, away from the lane.
    placed = env.data.body(PHANTOM_BODY).xpos[:2]
    assert np.linalg.norm(placed - np.asarray(sign.position)) == pytest.approx(0.05) and info["phantom_at"] == 1
    s, _ = sign.path.project(np.asarray(sign.position))
    lane = np.asarray(sign.path.pose_at(s)[:2])
    assert np.linalg.norm(placed - lane) > np.linalg.norm(np.asarray(sign.position) - lane)
    names = [env.model.geom(g).name for g in range(env.model.ngeom)
             if env.model.geom_bodyid[g] == env.model.body(PHANTOM_BODY).id]
    assert not [n for n in names if "pole" in n] and f"{PHANTOM_BODY}_panel" in names


@pytest.mark.parametrize("value", [{"remove": 7}, {"remove": True}, {"hide": 1}, [1]])
def test_a_bad_option_is_refused_naming_what_is_allowed(env, value):
    with pytest.raises(ValueError, match="sign_props"):
        env.reset(seed=0, options={"sign": 0, "sign_props": value})


@pytest.mark.parametrize("index", range(4))
def test_the_panel_s_edge_nearest_the_lane_is_where_the_sign_s_pole_is(env, index):
    env.reset(seed=0, options={"sign": index, "sign_props": {"remove": index, "phantom": index}})
    sign = stop_signs()[index]
    panel = env.model.geom(f"{PHANTOM_BODY}_panel")
    centre, rot = env.data.geom(panel.id).xpos[:2], env.data.geom(panel.id).xmat.reshape(3, 3)[:2, 1]
    half = panel.size[1]
    edges = [centre + k * half * rot for k in (-1.0, 1.0)]
    s, _ = sign.path.project(np.asarray(sign.position))
    lane = np.asarray(sign.path.pose_at(s)[:2])
    nearest = min(edges, key=lambda e: np.linalg.norm(e - lane))
    # Its nearest edge is the pole's place (give or take the 7 mm the panel stands behind the picture),
    # 0.24 m of panel reaching away from the lane.
    assert np.linalg.norm(nearest - np.asarray(sign.position)) < 0.008
