"""The scenario plan: what an episode is, made once from its spec and the map, before the env runs.

:func:`plan_episode` is pure. From a :class:`~racf.experiments.episode.spec.TrialSpec` it makes
the env's settings and reset options, the car's mission (the route, its targets, the cruise
speed) and the car's calibration (its build, read from the car's MJCF and the camera's
intrinsics). The env's reset reads the same route source (``racf.sim.world.route_plan``), and
nothing is read back out of the env: the runner hands the mission and the calibration to the
car and the referee.

A scenario (``racf.experiments.scenarios``) adds to the route's plan: env settings, world managers the
env runs, reset options, and what else it planned for its own criteria, metrics and end (``extras``).

Example:
    >>> from racf.experiments.episode import TrialSpec
    >>> from racf.experiments.episode.plan import plan_episode
    >>> plan = plan_episode(TrialSpec("clean", 2, 1.0, 0))
    >>> plan.reset_options, plan.mission.cruise_mps, len(plan.mission.targets)
    ({'sign': 2, 'cruise_speed': 1.0}, 1.0, 1)
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from racf.controllers import CameraModel
from racf.experiments.car.software import CarCalibration, Mission
from racf.experiments.episode.spec import TrialSpec
from racf.sim.env.config import EnvConfig
from racf.sim.sensors.calibration import car_build
from racf.sim.world.route_plan import longest_run_up_m, plan_route
from racf.sim.world.stop_signs import SIGN_GEOMETRIES

__all__ = ["EpisodePlan", "plan_episode", "reset_options", "env_settings", "car_calibration",
           "longest_run_up", "DRIVE_MAX_EPISODE_S"]

#: A drive's episode time limit, s.
DRIVE_MAX_EPISODE_S = 120.0


@dataclass(frozen=True)
class EpisodePlan:
    """Everything an episode is before it runs.

    Attributes:
        env_kwargs: the env's settings (``gym.make(racf.sim.ENV_ID, **env_kwargs)``).
        reset_options: ``env.reset(options=...)``.
        mission: the car's briefing.
        calibration: the car's build.
        control_dt_s: the car's loop period, s (the env's step).
        localisation: how the car localises (``qcar2``: its own filter; ``true``: the ablation).
        max_steps: the episode's step limit.
        start_s_m: where the ego car starts along the mission's path, m.
        extras: what the scenario planned beyond the route, by its own names, for its own metrics,
            criteria and end (other cars and where they meet the car's path, say); the engine reads none.
    """

    env_kwargs: dict
    reset_options: dict
    mission: Mission
    calibration: CarCalibration
    control_dt_s: float
    localisation: str
    max_steps: int
    start_s_m: float = 0.0
    extras: dict = field(default_factory=dict)


def env_settings(spec: TrialSpec) -> dict:
    """The env's settings for ``spec``: its sensors, its stop signs, (a drive) a longer limit, and
    what its scenario adds: settings and world managers (``Scenario.env_settings``, ``Scenario.world``)."""
    scenario, values = spec.scenario, spec.scenario_params
    kwargs = {"sensor_profile": spec.sensor_profile, "sign": SIGN_GEOMETRIES[spec.sign_geometry]}
    if scenario.target == "drive":
        kwargs["max_episode_s"] = DRIVE_MAX_EPISODE_S
    kwargs.update(scenario.env_settings(spec, values))
    world = scenario.world(spec, values)
    if world:
        kwargs["world"] = tuple(world)
    return kwargs


def reset_options(spec: TrialSpec) -> dict:
    """The env's reset options for the route of a spec: an approach to one target, or a drive."""
    drive = spec.drive
    if drive is not None:
        return drive.reset_options()
    options = {spec.scenario.target: spec.sign, "cruise_speed": spec.speed}
    run_up = spec.run_up_m if spec.run_up_m is not None else spec.scenario.run_up(spec)
    if run_up is not None:
        options["run_up_m"] = float(run_up)
    return options


def plan_episode(spec: TrialSpec, **env_kwargs) -> EpisodePlan:
    """The plan of one episode (``env_kwargs`` override the spec's env settings): the route's, then
    what the spec's scenario makes of it (``Scenario.plan``)."""
    kwargs = {**env_settings(spec), **env_kwargs}
    config = EnvConfig.from_kwargs(**kwargs)
    options = reset_options(spec)
    calibration = car_calibration(config.camera.width, config.camera.height)
    # The options name the target and the speed: the generator is never asked for them.
    route = plan_route(options, sign_geometry=config.sign, bumper_ahead_m=calibration.bumper_x_m,
                       max_speed_mps=config.vehicle.max_speed_mps, cruise_speeds_mps=config.cruise_speeds_mps,
                       rng=np.random.default_rng(0))
    mission = Mission(route.path, route.targets, route.cruise_mps, options.get("start_s_m"))
    dt = 1.0 / config.control_hz
    draft = EpisodePlan(kwargs, options, mission, calibration, dt, config.localisation,
                        int(round(config.max_episode_s / dt)), start_s_m=route.start_s)
    plan = spec.scenario.plan(spec, spec.scenario_params, draft)
    if spec.supervisor:  # a stage that cannot be supervised is said before the simulator starts
        from racf.experiments.car.assembly import supervisor_classes
        from racf.plugins import CAR_STAGES

        supervisor_classes([CAR_STAGES[name] for name in plan.mission.stages],
                           tuple(target.kind for target in plan.mission.targets))
    return plan


def longest_run_up(target: str, index: int, sign_geometry: str = "plate") -> float:
    """The longest ``TrialSpec.run_up_m`` an approach to this target allows, m."""
    config = EnvConfig.from_kwargs(sign=SIGN_GEOMETRIES[sign_geometry])
    calibration = car_calibration(config.camera.width, config.camera.height)
    return longest_run_up_m(target, index, config.sign, calibration.bumper_x_m)


@lru_cache(maxsize=8)
def car_calibration(width_px: int, height_px: int) -> CarCalibration:
    """The car's build as its software is configured with it: the camera's intrinsics at this
    resolution and the mounts of the camera, the LiDAR, the front bumper and the rear axle
    (``racf.sim.sensors.calibration``: read from the model the simulator drives)."""
    build = car_build(width_px, height_px)
    k = build.intrinsics
    return CarCalibration(CameraModel(width=k.width, fx=k.fx, cx=k.cx, fy=k.fy, cy=k.cy), build.camera_xy_m,
                          build.bumper_x_m, build.rear_axle_x_m, build.lidar_xy_m, build.camera_height_m)
