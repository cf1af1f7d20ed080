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
#: The attacks on the link to a defence service act on its answers, not on the observation.
ON_LINK = [name for name in BUILTIN if getattr(ATTACKS[name], "on_link", False)]


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


#: The attacks on the car ahead and on its radio run a following episode each (4-8 s): one of each kind in
#: the default run, every one in the slow run (CI's), so that the default run stays under its budget.
_SHOWN = {"lead_patch", "radio_jam"}


def _episode_cost(name: str):
    costly = (ATTACKS[name].acts_on == "vehicle" or name.startswith("radio_")) and name not in _SHOWN
    return pytest.param(name, marks=pytest.mark.slow) if costly else name


@pytest.mark.parametrize("name", [_episode_cost(n) for n in BUILTIN if n not in ON_LINK])
def test_the_attack_acts_in_a_real_closed_loop_episode(name):
    if ATTACKS[name].acts_on == "vehicle":  # an attack on a car ahead: in a scenario that declares one
        spec = TrialSpec(setting_name([name], "raw"), 1, 1.0, 0, target="lead_vehicle", t_atk=1.0,
                         scenario_params={"brake_t": 1.0, "broadcast": "on"}, attack_params={name: {"start_s": 0.5}})
    else:
        spec = TrialSpec(setting_name([name], "raw"), 1, 1.5, 0, run_up_m=1.5)
    tap, changed, active = None, [], []

    def make_env(spec):
        nonlocal tap
        tap = Tap(plain_env(**env_settings(spec)))
        return wrap_attacks(tap, spec)

    def on_step(env, obs, info, row):
        active.append(bool(info["attack_active"]))
        changed.append(any(not np.array_equal(obs[k], tap.last[k], equal_nan=True) for k in ("rgb", "depth", "lidar", "radio")))

    result, log = run_trial(spec, make_env=make_env, on_step=on_step, clean_pass=False)
    assert any(active) and np.isfinite(result.attack_start_s), "its window never opened"
    if name == "physical_patch":  # in the scene, so in what the env renders: the sign is lost instead
        assert (~log["detected"].astype(bool) & log["attack_active"].astype(bool)).any()
    else:
        assert any(c for c, a in zip(changed, active) if a), "the car received what the env rendered"
        assert not any(c for c, a in zip(changed, active) if not a), "it acted outside its window"


# link_delay and link_drop take 4-6.5 s each (a served episode): CI's slow stage runs them, the default
# run keeps link_spoof, the same window check on the same tap.
@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in ("link_delay", "link_drop") else n
                                  for n in ON_LINK])
def test_a_link_attack_acts_on_the_answers_in_its_window_only(name, service):
    """Served raw depth: the answer is the car's own depth unless the man in the middle acts."""
    # 120 ms: beyond any round trip the machine gives by itself, however loaded (45 ms was met outside the
    # window when the tests shared two cores with a mutation run).
    params = {"link_delay": {"delay_ms": 120.0, "jitter_ms": 0.0}, "link_spoof": {"distance_m": 7.5}}.get(name, {})
    spec = TrialSpec(setting_name([name], "raw"), 1, 1.5, 0, run_up_m=1.5, estimator_endpoint=service("raw"),
                     attack_params={name: params} if params else {}, estimator_timeout_ms=500.0)
    result, log = run_trial(spec, clean_pass=False)
    control = log["control"].astype(bool).to_numpy()
    active = log["attack_active"].astype(bool).to_numpy() & control
    assert active.any() and np.isfinite(result.attack_start_s), "its window never opened"
    acted = {"link_delay": log["service_rtt_ms"].to_numpy() >= 120.0,
             "link_drop": log["service_fallback"].to_numpy() == 1.0,
             # The spoofed answer arrives: it drives, or the car's own witnesses outvote it (issue 78).
             "link_spoof": (log["d_fused"].to_numpy() == 7.5)
             | (np.diff(log["service_outvoted"].to_numpy(float), prepend=0.0) > 0)}[name]
    assert acted[active].all(), "an answer in its window passed untouched"
    # After a lost answer the car asks again only after retry_s: its fallback outlasts the window.
    outside = control & ~active & (np.cumsum(active) == 0 if name == "link_drop" else True)
    if name == "link_spoof":  # outside, the honest answer may be outvoted too (raw depth's "no target")
        acted = log["d_fused"].to_numpy() == 7.5
    assert not acted[outside].any(), "it acted outside its window"
