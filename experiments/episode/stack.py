"""The parts an episode wires together: the env under the spec's attacks, the perception
pipelines, the distance estimator and the brakers (the one under test and the reference)."""

from __future__ import annotations

import gymnasium as gym

import sim
from controllers import CameraModel, ObstacleDetector, Perception, StopSignBraker
from experiments.episode.car import CarCalibration, sign_depth_at_line
from experiments.episode.estimators import make_estimator
from experiments.episode.spec import TrialSpec
from sim.attacks import ATTACKS
from sim.world.drives import RouteTarget

__all__ = ["default_env", "plain_env", "calibration", "Stack", "DRIVE_MAX_EPISODE_S"]

#: A drive's episode time limit, s.
DRIVE_MAX_EPISODE_S = 120.0

#: This process's plain envs by their settings. Building one (the model, the renderer's GL
#: context) costs about as much as 20 steps; ``reset(seed=...)`` restores all an episode sees.
_PLAIN_ENVS: dict[tuple, gym.Env] = {}


class _Shared(gym.Wrapper):
    """A process's shared plain env: closing an episode's wrappers leaves it open for the next."""

    def close(self) -> None:
        pass


def plain_env(**env_kwargs) -> gym.Env:
    """The env ``gym.make(sim.ENV_ID, **env_kwargs)``, built once per process and settings and
    handed to one episode at a time (episodes in a process run one after another)."""
    key = tuple(sorted(env_kwargs.items()))
    if key not in _PLAIN_ENVS:
        _PLAIN_ENVS[key] = gym.make(sim.ENV_ID, **env_kwargs)
    return _Shared(_PLAIN_ENVS[key])


def default_env(spec: TrialSpec, **env_kwargs) -> gym.Env:
    """The env of a spec: the process's plain env (:func:`plain_env`) wrapped in the spec's
    attacks (found in ``sim.attacks.ATTACKS``), all on the protocol's schedule (after a stable
    detection, inside the braking window; each draws its own duration). An attack's
    ``episode_params`` come from the spec's fields of those names (the patch's ``rho``)."""
    if spec.target == "drive":
        env_kwargs.setdefault("max_episode_s", DRIVE_MAX_EPISODE_S)
    env = plain_env(**env_kwargs)
    schedule = {"duration_s": spec.t_atk, "stable_steps": spec.attack_stable_steps}
    for name in spec.attacks:
        attack = ATTACKS[name]
        env = attack(env, **schedule, **{param: getattr(spec, param) for param in attack.episode_params})
    return env


def calibration(env: gym.Env) -> CarCalibration:
    """The car's build read once from its model: what the car's software is configured with."""
    u = env.unwrapped
    k = u.rig.intrinsics
    camera = u.model.camera("d435").pos
    return CarCalibration(CameraModel(width=k.width, fx=k.fx, cx=k.cx), (float(camera[0]), float(camera[1])),
                          float(u.model.site("front_bumper").pos[0]))


class Stack:
    """Perception (one pipeline per target kind), the estimator and, per target, two brakers:
    the one under test (fed the estimator) and the reference that defines t* (fed d_true
    while the target is in view). ``calibration`` is the car's build (:func:`calibration`)."""

    def __init__(self, env: gym.Env, spec: TrialSpec, estimator=None) -> None:
        self.calibration = calibration(env)
        camera = self.calibration.camera
        self.spec = spec
        self.perceptions = {"sign": Perception(camera),
                            "obstacle": Perception(camera, detector=ObstacleDetector(), target="obstacle")}
        self.estimator = estimator if estimator is not None else make_estimator(spec.estimator)

    def begin(self, target: RouteTarget) -> tuple[Perception, StopSignBraker, StopSignBraker]:
        """Fresh state for the next target of the route."""
        depth_at_line = sign_depth_at_line(self.calibration, target)
        self.estimator.reset()
        perception = self.perceptions[target.kind]
        perception.reset()
        return (perception, StopSignBraker(self.spec.braking, depth_at_line),
                StopSignBraker(self.spec.braking, depth_at_line))
