"""The parts an episode wires together: the env under the spec's attacks, and the car's software
built from the episode's plan (:mod:`~racf.experiments.episode.plan`: its build, its mission)
with its perception pipelines and estimator. The car itself is :class:`racf.experiments.car.software.Car`."""

from __future__ import annotations

import gymnasium as gym

from racf import sim
from racf.controllers import LidarTargetConfig, LidarTargetTracker, ObstacleDetector, Perception, SizeDistance
from racf.controllers.detectors import make_detector
from racf.experiments.car.software import Car, CarCalibration
from racf.experiments.car.stage import StageContext
from racf.experiments.car.estimators import make_estimator
from racf.experiments.car.existence import ExistenceStage
from racf.experiments.episode.plan import DRIVE_MAX_EPISODE_S, EpisodePlan, env_settings
from racf.experiments.episode.spec import TrialSpec
from racf.experiments.car.assembly import car_stages as assembled_stages
from racf.sim.attacks import ATTACKS
from racf.sim.world.stop_signs import SIGN_FACE_ACROSS_FLATS_M, SIGN_RED_FACE_ACROSS_FLATS_M

__all__ = ["default_env", "wrap_attacks", "plain_env", "build_car", "car_keys", "link_endpoint", "existence_stage", "car_stages", "tracker", "outlined_size_m", "OUTLINED_SIZE_M",
           "DRIVE_MAX_EPISODE_S"]

#: The map's size, across flats, of each part of the sign a detector may outline (``BlobDetector.outline``).
OUTLINED_SIZE_M = {"red_face": SIGN_RED_FACE_ACROSS_FLATS_M, "face": SIGN_FACE_ACROSS_FLATS_M}


def outlined_size_m(detector) -> float:
    """The size of what ``detector``'s masks outline (a plug-in that does not say: the red face)."""
    outline = getattr(detector, "outline", "red_face")
    if outline not in OUTLINED_SIZE_M:
        raise ValueError(f"detector {type(detector).__name__} outlines {outline!r}; allowed: "
                         f"{', '.join(OUTLINED_SIZE_M)}")
    return OUTLINED_SIZE_M[outline]


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
    return wrap_attacks(plain_env(**{**env_settings(spec), **env_kwargs}), spec)


def wrap_attacks(env: gym.Env, spec: TrialSpec) -> gym.Env:
    """``env`` under the spec's attacks, each on the protocol's schedule (:func:`default_env`)."""
    schedule = {"duration_s": spec.t_atk, "stable_steps": spec.attack_stable_steps}
    for name in spec.attacks:
        attack = ATTACKS[name]
        env = attack(env, **schedule, **{param: getattr(spec, param) for param in attack.episode_params},
                     **spec.attack_params.get(name, {}))
    return env


def tracker(calibration: CarCalibration) -> LidarTargetTracker:
    """The LiDAR reference's tracker, configured with where the car's LiDAR and camera sit."""
    return LidarTargetTracker(LidarTargetConfig(lidar_position_m=calibration.lidar_xy_m,
                                                camera_position_m=calibration.camera_xy_m))


def build_car(spec: TrialSpec, plan: EpisodePlan, estimator=None, env: gym.Env | None = None) -> Car:
    """The car's software for one episode of ``spec``: its build and mission from ``plan``, its
    loop at the env's rate, the controller at ``spec.control_hz``. The calibration configures
    every part that needs the car's geometry (the trackers, an estimator that asks for it). A
    served defence is reached through the link attacks among ``env``'s wrappers, if any."""
    calib = plan.calibration
    every = max(1, int(round(1.0 / plan.control_dt_s / spec.control_hz))) if spec.control_hz else 1
    detector = make_detector(spec.detector)
    # The map knows the signs' size: the size witness measures what the detector outlines against it.
    size = SizeDistance(calib.camera, outlined_size_m(detector))
    perceptions = {"sign": Perception(calib.camera, detector=detector, lidar=tracker(calib), size=size),
                   "obstacle": Perception(calib.camera, detector=ObstacleDetector(), lidar=tracker(calib),
                                          target="obstacle")}
    if estimator is None and spec.estimator_endpoint is not None:
        from racf.experiments.link.remote import RemoteEstimator

        estimator = RemoteEstimator(link_endpoint(env, spec), spec.estimator, spec.estimator_options,
                                    spec.estimator_timeout_ms, keys=car_keys(spec), onboard=onboard_defence(spec))
    estimator = estimator if estimator is not None else make_estimator(spec.estimator, spec.estimator_options)
    configure = getattr(estimator, "use_calibration", None)
    if callable(configure):
        configure(calib)
    return Car(calib, plan.mission, perceptions, estimator, spec.braking, plan.control_dt_s, every, plan.localisation,
               existence_stage(estimator, calib, spec.detector), car_stages(spec, plan, fleet_keys(env)))


def fleet_keys(env: gym.Env | None) -> dict:
    """The public keys of the episode's fleet, as the car is provisioned with them (its world's radio
    draws the fleet at reset; the car gets the public keys only)."""
    radio = getattr(env.unwrapped, "radio", None) if env is not None else None
    return radio.fleet.trust_store() if radio is not None else {}


def onboard_defence(spec: TrialSpec):
    """The defence the car runs itself beside a served one (None: ``raw``, its own depth distance): ODCA from
    its ONNX export, as the car runs it, or the named estimator with its defaults."""
    if spec.estimator_fallback == "raw":
        return None
    if spec.estimator_fallback == "odca":
        return make_estimator("odca", {"runtime": "onnx"})
    return make_estimator(spec.estimator_fallback, {})


def car_stages(spec: TrialSpec, plan: EpisodePlan, trusted: dict | None = None) -> tuple:
    """The car's stages (:func:`racf.experiments.car.assembly.car_stages`): those the plan's mission
    engages, each built on the car's build with its own instance of the spec's defence, and the
    supervision the spec asks for; ``trusted``: the fleet's public keys the car is provisioned with."""
    if not plan.mission.stages and not spec.supervisor:
        return ()
    calib = plan.calibration

    def make_defence():
        estimator = make_estimator(spec.estimator, spec.estimator_options)
        configure = getattr(estimator, "use_calibration", None)
        if callable(configure):
            configure(calib)
        return estimator

    context = StageContext(calib.camera, calib.camera_xy_m, calib.camera_height_m, calib.lidar_xy_m,
                           calib.bumper_x_m - calib.camera_xy_m[0], make_defence, spec.detector,
                           plan.mission.target_decel_mps2, plan.mission.target_accel_mps2, dict(trusted or {}))
    kinds = tuple(dict.fromkeys(target.kind for target in plan.mission.targets))
    return assembled_stages(plan.mission.stages, context, spec.supervisor, kinds)


def car_keys(spec: TrialSpec):
    """The car's CURVE keys for its link to the service (None: a plain link)."""
    from racf.experiments.link.curve import CarKeys

    return None if spec.estimator_keys is None else CarKeys.load(spec.estimator_keys, spec.estimator_car)


def link_endpoint(env: gym.Env | None, spec: TrialSpec) -> str:
    """Where the car reaches its served defence: the service itself, or, under link attacks, a man in
    the middle (:class:`~racf.experiments.link.relay.LinkRelay`) closed with the env."""
    from racf.sim.attacks.link import link_attacks

    attacks = link_attacks(env) if env is not None else []
    if not attacks:
        return spec.estimator_endpoint
    from racf.experiments.link.relay import LinkRelay

    relay = LinkRelay(spec.estimator_endpoint, attacks)
    attacks[0].bind_link(relay)
    return relay.endpoint


def existence_stage(estimator, calibration: CarCalibration, detector: str) -> ExistenceStage | None:
    """The existence stage for a defence that answers ``stands()`` (``existence = True``), with its
    ``second_detector`` beside the car's (the other of the two when it names the car's own); None
    for any other defence."""
    if not getattr(estimator, "existence", False):
        return None
    second = getattr(estimator, "second_detector", None)
    if second == detector:
        second = "classical" if detector != "classical" else "learned"
    return ExistenceStage(calibration, make_detector(second) if second else None)
