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
    assert np.allclose(env.data.body(PHANTOM_BODY).xpos[:2], sign.position) and info["phantom_at"] == 1
    names = [env.model.geom(g).name for g in range(env.model.ngeom)
             if env.model.geom_bodyid[g] == env.model.body(PHANTOM_BODY).id]
    assert not [n for n in names if "pole" in n] and f"{PHANTOM_BODY}_panel" in names


@pytest.mark.parametrize("value", [{"remove": 7}, {"remove": True}, {"hide": 1}, [1]])
def test_a_bad_option_is_refused_naming_what_is_allowed(env, value):
    with pytest.raises(ValueError, match="sign_props"):
        env.reset(seed=0, options={"sign": 0, "sign_props": value})
