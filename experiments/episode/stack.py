"""The parts an episode wires together: the env under the spec's attacks, and what the car's
software is configured with before it starts (its build, its mission, its perception pipelines
and estimator). The car itself is :class:`racf.experiments.episode.car.Car`."""

from __future__ import annotations

import gymnasium as gym

from racf import sim
from racf.controllers import CameraModel, ObstacleDetector, Perception
from racf.controllers.detectors import make_detector
from racf.experiments.episode.car import Car, CarCalibration, Mission
from racf.experiments.episode.estimators import make_estimator
from racf.experiments.episode.spec import TrialSpec
from racf.sim.attacks import ATTACKS
from racf.sim.world.stop_signs import SIGN_GEOMETRIES

__all__ = ["default_env", "plain_env", "calibration", "mission", "build_car", "DRIVE_MAX_EPISODE_S"]

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
    attacks (found in ``racf.sim.attacks.ATTACKS``), all on the protocol's schedule (after a stable
    detection, inside the braking window; each draws its own duration). An attack's
    ``episode_params`` come from the spec's fields of those names (the patch's ``rho``), its
    other settings from ``spec.attack_params``."""
    if spec.target == "drive":
        env_kwargs.setdefault("max_episode_s", DRIVE_MAX_EPISODE_S)
    env_kwargs.setdefault("sensor_profile", spec.sensor_profile)
    env_kwargs.setdefault("sign", SIGN_GEOMETRIES[spec.sign_geometry])
    env = plain_env(**env_kwargs)
    schedule = {"duration_s": spec.t_atk, "stable_steps": spec.attack_stable_steps}
    for name in spec.attacks:
        attack = ATTACKS[name]
        env = attack(env, **schedule, **{param: getattr(spec, param) for param in attack.episode_params},
                     **spec.attack_params.get(name, {}))
    return env


def calibration(env: gym.Env) -> CarCalibration:
    """The car's build read once from its model: what the car's software is configured with."""
    u = env.unwrapped
    k = u.rig.intrinsics
    camera = u.model.camera("d435").pos
    return CarCalibration(CameraModel(width=k.width, fx=k.fx, cx=k.cx, fy=k.fy), (float(camera[0]), float(camera[1])),
                          float(u.model.site("front_bumper").pos[0]), float(u.model.body("wheel_rl").pos[0]))


def mission(env: gym.Env, options: dict) -> Mission:
    """The car's briefing for the episode ``env`` was just reset to with ``options``: the route's
    path and targets from the map (stop signs; and the crate's place, which the operator tells
    the car: it is not found by the car's sensors), the cruise speed and the start along the route."""
    u = env.unwrapped
    return Mission(u.route_path, u.route_targets, float(options["cruise_speed"]), options.get("start_s_m"))


def build_car(env: gym.Env, spec: TrialSpec, brief: Mission, estimator=None) -> Car:
    """The car's software for one episode of ``spec`` (its build read from the model, its loop at
    the env's rate, the controller at ``spec.control_hz``)."""
    calib = calibration(env)
    config = env.unwrapped.config
    every = max(1, int(round(config.control_hz / spec.control_hz))) if spec.control_hz else 1
    perceptions = {"sign": Perception(calib.camera, detector=make_detector(spec.detector)),
                   "obstacle": Perception(calib.camera, detector=ObstacleDetector(), target="obstacle")}
    return Car(calib, brief, perceptions, estimator if estimator is not None else make_estimator(spec.estimator, spec.estimator_options),
               spec.braking, 1.0 / config.control_hz, every, config.localisation)
