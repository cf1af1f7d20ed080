"""The car drives on what it senses: scrambling the ground truth in ``info`` changes nothing it does.

The scrambler sits outside the attack wrappers (an attacker may see the world; the car may
not) and replaces every ground-truth value the runner receives, with its own generator. The
car's actions, its distance estimate and its pose estimate must come out bit-identical; the
referee's columns (d_true, the reference braker) are the only ones allowed to change.
"""

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest

from racf.experiments.episode import TrialSpec, plan_episode, run_trial
from racf.experiments.episode.stack import car_stages, default_env

#: What the car does and works out; none of it may depend on ``info``.
CAR_COLUMNS = ["speed_cmd", "steer_cmd", "d_fused", "d_meas", "lidar", "detected", "brake", "phase", "slot",
               "x_est", "y_est", "yaw_est"]
#: ``time`` and ``dist_to_stop_line`` stay: the runner (the experimenter, not the car) ends
#: the episode on them, and both runs must last the same number of steps to be compared.
KEPT = {"time", "dist_to_stop_line", "collision", "off_road", "attack", "attack_active"}


class ScrambledInfo(gym.Wrapper):
    """Passes observations and actions through; every ground-truth entry of ``info`` is junk."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self._rng = np.random.default_rng(12345)

    def _scramble(self, info: dict) -> dict:
        out = dict(info)
        for key, value in info.items():
            if key in KEPT:
                continue
            if isinstance(value, (bool, np.bool_)):
                out[key] = not value
            elif isinstance(value, np.ndarray) and value.dtype == bool:
                out[key] = ~value
            elif isinstance(value, np.ndarray):
                out[key] = value + self._rng.normal(0.0, 0.3, value.shape)
            elif isinstance(value, (int, float, np.floating, np.integer)):
                out[key] = value + self._rng.uniform(0.2, 0.5)
        return out

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        return obs, self._scramble(info)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._scramble(info)


@pytest.mark.parametrize("spec", [TrialSpec("attack+odca", 0, 1.5, 1),
                                  # Two other cars crossing: their states in info are scrambled too.
                                  pytest.param(TrialSpec("attack+odca", 3, 1.5, 1, target="cross_traffic",
                                                         scenario_params={"cars": 2}), marks=pytest.mark.slow),
                                  # The existence vote's witnesses, a sticker up from the start on a mapped sign.
                                  pytest.param(TrialSpec("clean+physical_patch+vote", 1, 1.5, 1, target="stale_map",
                                                         attack_params={"physical_patch": {"from_start": True}}),
                                               marks=pytest.mark.slow),
                                  # A car ahead that brakes early, its depth read far from 0.5 s: its pose and
                                  # speed in info are scrambled too (a short episode for the default run).
                                  TrialSpec("clean+lead_patch+odca", 1, 1.0, 1, target="lead_vehicle",
                                            scenario_params={"brake_t": 1.0},
                                            attack_params={"lead_patch": {"start_s": 0.5}}),
                                  # The same under the supervisor (its chain, its carried target, its lane return):
                                  # 18 s, in the slow run.
                                  pytest.param(TrialSpec("clean+lead_patch+odca", 1, 1.0, 1, target="lead_vehicle",
                                                         scenario_params={"brake_t": 1.0}, supervisor=True,
                                                         attack_params={"lead_patch": {"start_s": 0.5}}),
                                               marks=pytest.mark.slow),
                                  # The lead's whole default profile: the long episode, in the slow run.
                                  pytest.param(TrialSpec("clean+lead_patch+odca", 1, 1.0, 1, target="lead_vehicle"),
                                               marks=pytest.mark.slow)],
                         ids=["empty", "traffic", "existence", "lead", "lead-supervised", "lead-long"])
def test_the_car_does_the_same_with_info_scrambled(spec):
    result, log = run_trial(spec, clean_pass=False)
    _, blind = run_trial(spec, make_env=lambda s: ScrambledInfo(default_env(s)), clean_pass=False)
    assert len(log) > 50 and log["attack_active"].any()
    witnesses = [c for c in log.columns if c.startswith("wit_") or c == "stands"]
    # Every column an engaged car stage declares is the car's too (following's: the lead's witnesses, its cap).
    staged = [c.name for stage in car_stages(spec, plan_episode(spec)) for c in stage.columns]
    assert bool(staged) == (spec.target == "lead_vehicle") and set(staged) <= set(log.columns)
    assert bool(witnesses) == (spec.estimator == "vote")
    # A scenario may end its episode on the referee's truth (the lead's: once the car stands behind it, by its
    # true speed): scrambled, the experiment may run on longer. The car must do the same while both run.
    n = min(len(log), len(blind))
    assert n > 50 and (n == len(log) or spec.target == "lead_vehicle")
    pd.testing.assert_frame_equal(blind[CAR_COLUMNS + witnesses + staged].iloc[:n], log[CAR_COLUMNS + witnesses + staged].iloc[:n])
    # The scrambler did reach the runner: the referee's ground truth differs.
    if log["d_true"].notna().any():  # (a following episode may end before its sign comes into view)
        assert not np.allclose(blind["d_true"].iloc[:n].fillna(-1), log["d_true"].iloc[:n].fillna(-1))
    assert not np.allclose(blind["x"].iloc[:n], log["x"].iloc[:n])
    if spec.target == "cross_traffic":
        assert not np.allclose(blind["traffic1_x"], log["traffic1_x"])
    if spec.target == "lead_vehicle":
        assert not np.allclose(blind["lead_x"].iloc[:n], log["lead_x"].iloc[:n]) and log["lead_detected"].any()
