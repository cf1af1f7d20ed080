"""The sticker attack: it goes up with the protocol's window (or at the start) and stays."""

import gymnasium as gym
import numpy as np
import pytest

from racf import sim
from racf.sim.attacks import ATTACKS, PhysicalPatch


def _run(env, steps=30):
    obs, info = env.reset(seed=1, options={"sign": 2, "cruise_speed": 1.0})
    shown = [env.unwrapped.model.geom_group[env.unwrapped.stickers.geoms[2]] == 0]
    marks = [info["attack_active"]]
    for _ in range(steps):
        obs, _, term, trunc, info = env.step(np.array([0.5, 0.0], np.float32))
        shown.append(env.unwrapped.model.geom_group[env.unwrapped.stickers.geoms[2]] == 0)
        marks.append(info["attack_active"])
        if term or trunc:
            break
    return np.array(shown), np.array(marks)


def test_the_sticker_goes_up_with_the_window_and_stays():
    env = PhysicalPatch(gym.make(sim.ENV_ID), texture="natural", duration_s=0.2, trigger="always")
    shown, marks = _run(env)
    start = int(np.argmax(shown))
    assert 0 < start and shown[start:].all() and np.array_equal(shown, marks)
    gone = PhysicalPatch(gym.make(sim.ENV_ID), texture="natural", duration_s=0.2, stays=False, trigger="always")
    shown2, _ = _run(gone)
    assert shown2.any() and not shown2[-1]


def test_from_start_the_first_frame_shows_it():
    plain = gym.make(sim.ENV_ID)
    obs0, _ = plain.reset(seed=1, options={"sign": 2, "cruise_speed": 1.0, "run_up_m": 0.6})
    env = PhysicalPatch(gym.make(sim.ENV_ID), texture="natural", from_start=True)
    obs1, info = env.reset(seed=1, options={"sign": 2, "cruise_speed": 1.0, "run_up_m": 0.6})
    assert info["attack_active"] and info["attack"] == ("physical_patch",)
    assert not np.array_equal(obs0["rgb"], obs1["rgb"])


@pytest.mark.parametrize("params, match", [({"size": 0.8}, "area_share"), ({"position": [0.45, 0.0]}, "plate"),
                                           ({"texture": "nope"}, "shipped"), ({"from_start": 1}, "from_start")])
def test_bad_parameters_fail_before_any_episode(params, match):
    with pytest.raises(ValueError, match=match):
        ATTACKS["physical_patch"].check_params(params)
