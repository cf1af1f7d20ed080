"""Every registered attack acts in a real closed-loop episode (the MuJoCo env, the car's stack, the
protocol's schedule), not only on the stub env: its window opens, and what the car receives
differs from what the env rendered (the physical sticker, which is in the scene itself, makes the
car's detector lose the sign)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from racf.experiments.episode import TrialSpec, run_trial, setting_name
from racf.experiments.episode.plan import env_settings
from racf.experiments.episode.stack import plain_env, wrap_attacks
from racf.plugins import ATTACKS

BUILTIN = [name for name in ATTACKS if ATTACKS.plugin(name).builtin]


class Tap(gym.Wrapper):
    """Keeps the last observation the env itself returned, under the attacks."""

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self.last = obs
        return obs, info

    def step(self, action):
        out = self.env.step(action)
        self.last = out[0]
        return out


def test_every_builtin_attack_is_tested_here():
    assert len(BUILTIN) >= 11 and {"physical_patch", "lidar_spoof", "delay", "frustum_spoof"} <= set(BUILTIN)


@pytest.mark.parametrize("name", BUILTIN)
def test_the_attack_acts_in_a_real_closed_loop_episode(name):
    spec = TrialSpec(setting_name([name], "raw"), 1, 1.5, 0, run_up_m=1.5)
    tap, changed, active = None, [], []

    def make_env(spec):
        nonlocal tap
        tap = Tap(plain_env(**env_settings(spec)))
        return wrap_attacks(tap, spec)

    def on_step(env, obs, info, row):
        active.append(bool(info["attack_active"]))
        changed.append(any(not np.array_equal(obs[k], tap.last[k], equal_nan=True) for k in ("rgb", "depth", "lidar")))

    result, log = run_trial(spec, make_env=make_env, on_step=on_step, clean_pass=False)
    assert any(active) and np.isfinite(result.attack_start_s), "its window never opened"
    if name == "physical_patch":  # in the scene, so in what the env renders: the sign is lost instead
        assert (~log["detected"].astype(bool) & log["attack_active"].astype(bool)).any()
    else:
        assert any(c for c, a in zip(changed, active) if a), "the car received what the env rendered"
        assert not any(c for c, a in zip(changed, active) if not a), "it acted outside its window"
