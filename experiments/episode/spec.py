"""What an episode runs: the setting (attacks and estimator), target, speed, seed, attack
parameters and timing, and the id that names its result.

A setting is a ``+``-joined name: ``clean`` or ``attack`` (the image-space occluder ``patch_occlusion``), then any
extra attacks (``lidar_spoof``, ``lidar_dropout``, ``depth_blackout``, ``depth_bias``,
``confidence_degradation``, ``physical_patch``, ...; ``clean+depth_bias`` is the bias alone), then the estimator when it is not raw
depth (``odca``, ``ekf``, ``chronos``). The paper's table uses ``clean``, ``clean+odca``,
``attack``, ``attack+odca``, ``attack+ekf``, ``attack+chronos`` and, beyond the paper,
``attack+lidar_spoof+odca``.

The trial id hashes the spec, every config the episode uses and the code version (the
source of the packages and the shipped checkpoints), so a resumed batch never reuses a
result that other code or configs produced.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field

import numpy as np

from racf.controllers import BrakingConfig
from racf.controllers.detectors import DETECTORS
from racf.experiments.car.estimators import ESTIMATORS, check_options
from racf.experiments.link.wire import DEFAULT_TIMEOUT_MS
from racf.provenance import code_version
from racf.sim.attacks import ATTACKS
from racf.sim.attacks.schedule import as_range
from racf.sim.env.config import SENSOR_PROFILES
from racf.sim.world.stop_signs import SIGN_GEOMETRIES
from racf.sim.world.drives import DriveSpec, draw_drive
from racf.plugins import METRICS, SCENARIOS

__all__ = ["TrialSpec", "parse_setting", "setting_name", "EPISODE_CODE", "TARGETS", "DRIVE_S", "STRONG_RHO",
           "STRONG_T_ATK_S", "extra_attacks", "TABLE_SETTINGS", "plugin_sources"]

#: The one scenario whose parameters specs held as fields of their own before scenarios were plug-ins:
#: its name, and each old field's parameter and default.
_LEGACY_SCENARIO = ("cross_traffic", {"traffic_cars": ("cars", 0), "traffic_gap_s": ("gap_s", 0.0),
                                      "traffic_speed": ("speed", 1.0)})

#: What a route is built around (``TrialSpec.sign`` is the index): the four stop signs or the
#: two crates; or a ``drive`` (index 0), a random route drawn from the seed that meets >= 2 targets.
#: A scenario (``TrialSpec.target``) names one of these kinds as its ``target``.
TARGETS = {"sign": 4, "obstacle": 2, "drive": 1}
#: How long a drive is drawn to last, s.
DRIVE_S = (20.0, 60.0)
#: The protocol's strong regime.
STRONG_RHO = (0.9, 1.0)
STRONG_T_ATK_S = (0.5, 3.0)


def extra_attacks() -> tuple[str, ...]:
    """Attacks that may join (or replace) the patch in a setting: every registered attack but
    the patch, in the registry's order, plug-ins included (read at each call: a plug-in
    registered after import counts)."""
    return tuple(name for name in ATTACKS if name != "patch_occlusion")


#: The env's step rate, Hz (attack timing is counted in its steps).
ENV_HZ = 50.0
#: The paper's closed-loop table, plus the LiDAR spoof under ODCA.
TABLE_SETTINGS = ("clean", "clean+odca", "attack", "attack+odca", "attack+ekf", "attack+chronos",
                  "attack+lidar_spoof+odca")


def parse_setting(setting: str) -> tuple[tuple[str, ...], str]:
    """``"attack+lidar_spoof+odca"`` -> (("patch_occlusion", "lidar_spoof"), "odca"); ValueError names what is allowed."""
    if not isinstance(setting, str) or not setting:
        raise ValueError(f"setting must be a non-empty string, got {setting!r}")
    base, *rest = setting.split("+")
    if base not in ("clean", "attack"):
        raise ValueError(f"a setting starts with 'clean' or 'attack', got {setting!r}")
    estimator = "raw"
    if rest and rest[-1] in ESTIMATORS:
        estimator = rest.pop()
    extra = extra_attacks()
    unknown = [r for r in rest if r not in extra]
    for part in unknown:  # an installed part that failed to load: say why, not "unknown"
        for registry in (ESTIMATORS, ATTACKS):
            if part in registry.broken:
                registry.plugin(part)
    if unknown:
        raise ValueError(f"unknown part(s) {unknown} of setting {setting!r}: after 'clean'/'attack' come extra "
                         f"attacks {extra}, then an estimator {tuple(ESTIMATORS)}")
    attacks = (("patch_occlusion",) if base == "attack" else ()) + tuple(rest)
    return attacks, estimator


def setting_name(attacks: tuple[str, ...] | list[str], estimator: str = "raw") -> str:
    """The setting of a set of attacks (``patch_occlusion`` and/or :func:`extra_attacks`) and an estimator."""
    attacks, extra = tuple(attacks), extra_attacks()
    unknown = [a for a in attacks if a != "patch_occlusion" and a not in extra]
    if unknown:
        raise ValueError(f"unknown attack(s) {unknown}; choose from {tuple(ATTACKS)}")
    if estimator not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {tuple(ESTIMATORS)}, got {estimator!r}")
    parts = ["attack" if "patch_occlusion" in attacks else "clean"] + [a for a in extra if a in attacks]
    name = "+".join(parts + ([estimator] if estimator != "raw" else []))
    parse_setting(name)
    return name


@dataclass(frozen=True)
class TrialSpec:
    """One episode.

    Attributes:
        setting: attacks and estimator (see the module docstring).
        sign: the target's index (a stop sign 0-3, a crate 0-1, or 0 for a drive).
        speed: cruise speed (a drive's nominal speed), m/s.
        seed: the episode's seed (env noise, attack draws, a drive's route).
        rho, t_atk: the patch's coverage share and duration, s: (low, high) uniform ranges.
        target: the scenario (``racf.plugins.SCENARIOS``): ``sign``, ``obstacle``, ``drive``,
            ``cross_traffic`` or a plug-in's.
        drive_s: how long a drive is drawn to last, s.
        stable_steps: env steps the sign must be visible before an attack may start; None:
            ``confirm_frames + 3`` controller steps (and the delay), so that the controller
            has a confirmed track (the detector may lag the ground-truth visibility by a step
            or two).
        delay_ms: perception-to-actuation delay (0: off). The paper's offboard loop: 49 ms.
        control_hz: the controller's rate (None: every 50 Hz step); the action is held between.
        braking: the braking controller's parameters.
        sensor_profile: the env's sensors (``racf.sim.env.config.SENSOR_PROFILES``): ``qcar2``
            (the default: the A2M12 through Quanser's driver, the camera at 30 Hz, the car's
            own localisation) or ``ideal`` (env v2's sensors and the true pose, an ablation).
        sign_geometry: the stop signs' build (``racf.sim.world.stop_signs.SIGN_GEOMETRIES``):
            ``plate`` (the default: the LiDAR's scan plane meets the plate) or ``pole`` (it
            meets only the pole).
        attack_params: per attack of the setting, constructor arguments to set (e.g.
            ``{"stealth_ramp": {"rate_mps": 3.0}}``; ``AttackWrapper.settable_params``).
        detector: the car's stop-sign detector (``racf.controllers.detectors.DETECTORS``):
            ``classical`` (colour and shape, the default), ``learned`` (the segmenter) or a plug-in.
        estimator_options: keyword arguments for the setting's estimator (e.g.
            ``{"checkpoint": "outputs/odca-head"}``); a path's content enters the trial id.
        run_up_m: how far before the stop line the front bumper starts an approach, m (None: 3 m,
            or the longest the lane allows); not for a drive.
        scenario_params: the scenario's parameters (its ``params`` declare them); the spec holds
            every one, the defaults filled in.
        metrics: metrics to score beyond those every episode has (``racf.plugins.METRICS``; a
            scenario adds its own, ``Scenario.metrics``).
        estimator_endpoint: run the estimator in a ``racf serve`` process at this address
            (``tcp://HOST:PORT``) instead of in the car's (None: in the car's). The measured round
            trip delays the car; the id records that a service ran it, not where it listened.
        estimator_timeout_ms: with an endpoint, how long the car waits for an answer before it
            falls back to its onboard defence for the step, ms.
        estimator_fallback: with an endpoint, the car's onboard defence, run every step beside the
            served one and driving where the service gives no answer the car may act on: an estimator's
            name (``odca``, the default: ODCA from its ONNX export, as the car runs it), or ``raw``, the
            car's own depth distance unrepaired (before issue 70, the only fallback).
        estimator_keys: with an endpoint, the key folder of ``racf serve keys`` whose car pair and
            service key make the link CurveZMQ (None: a plain link). The id records that the link was
            authenticated, not where the keys lie.
        supervisor: run the supervisor (runtime assurance, ``racf.experiments.car.supervisor``) over the
            defence, in place of the stage it supervises (the following stage); False: the defence alone.
        estimator_car: with keys, the car whose pair (``cars/NAME.key_secret``) the car uses (None:
            the only one the folder holds). Not in the id: which car's key, not what ran.
    """

    setting: str
    sign: int
    speed: float
    seed: int
    rho: tuple[float, float] = STRONG_RHO
    t_atk: tuple[float, float] = STRONG_T_ATK_S
    target: str = "sign"
    drive_s: tuple[float, float] = DRIVE_S
    stable_steps: int | None = None
    delay_ms: float = 0.0
    control_hz: float | None = None
    braking: BrakingConfig = field(default_factory=BrakingConfig)
    sensor_profile: str = "qcar2"
    sign_geometry: str = "plate"
    attack_params: dict = field(default_factory=dict)
    detector: str = "classical"
    estimator_options: dict = field(default_factory=dict)
    run_up_m: float | None = None
    scenario_params: dict = field(default_factory=dict)
    metrics: tuple[str, ...] = ()
    estimator_endpoint: str | None = None
    estimator_timeout_ms: float = DEFAULT_TIMEOUT_MS
    estimator_keys: str | None = None
    estimator_car: str | None = None
    supervisor: bool = False
    estimator_fallback: str = "odca"

    def __post_init__(self) -> None:
        attacks, estimator = parse_setting(self.setting)
        try:
            check_options(estimator, self.estimator_options)
        except ValueError as err:
            raise ValueError(f"estimator_options: {err}") from None
        if not isinstance(self.attack_params, dict):
            raise ValueError(f"attack_params must be a dict of attack -> {{parameter: value}}, got {self.attack_params!r}")
        for name, params in self.attack_params.items():
            if name not in attacks:
                raise ValueError(f"attack_params names {name!r}, which setting {self.setting!r} does not run "
                                 f"(its attacks: {list(attacks)})")
            ATTACKS[name].check_params(params)
        if self.target not in SCENARIOS:
            raise ValueError(f"target must be a scenario, one of {tuple(SCENARIOS)}, got {self.target!r}")
        scenario = self.scenario
        object.__setattr__(self, "scenario_params", scenario.values(self.scenario_params))
        kind = scenario.target
        for name in attacks:
            if kind not in ATTACKS[name].targets:
                raise ValueError(f"attack {name!r} cannot act on target {self.target!r}: it acts on "
                                 f"{list(ATTACKS[name].targets)}")
        _check_declared_targets(self, attacks)
        if self.sensor_profile not in SENSOR_PROFILES:
            raise ValueError(f"sensor_profile must be one of {tuple(SENSOR_PROFILES)}, got {self.sensor_profile!r}")
        if self.sign_geometry not in SIGN_GEOMETRIES:
            raise ValueError(f"sign_geometry must be one of {tuple(SIGN_GEOMETRIES)}, got {self.sign_geometry!r}")
        if self.detector not in DETECTORS:
            raise ValueError(f"detector must be one of {tuple(DETECTORS)}, got {self.detector!r}")
        if self.sign not in range(TARGETS[kind]):
            raise ValueError(f"{kind} index must be 0..{TARGETS[kind] - 1}, got {self.sign!r}")
        if not 0.1 <= self.speed <= 3.0:
            raise ValueError(f"speed must be in [0.1, 3.0] m/s, got {self.speed!r}")
        object.__setattr__(self, "rho", as_range("rho", self.rho, 0.0, 1.0))
        object.__setattr__(self, "t_atk", as_range("t_atk", self.t_atk, 0.0, 60.0))
        object.__setattr__(self, "drive_s", as_range("drive_s", self.drive_s, 5.0, 100.0))
        if self.stable_steps is not None and not (isinstance(self.stable_steps, int) and 1 <= self.stable_steps <= 500):
            raise ValueError(f"stable_steps must be an int in [1, 500] or None, got {self.stable_steps!r}")
        if not 0.0 <= self.delay_ms <= 1000.0:
            raise ValueError(f"delay_ms must be in [0, 1000] ms, got {self.delay_ms!r}")
        if self.run_up_m is not None and (kind == "drive" or isinstance(self.run_up_m, bool)
                                          or not isinstance(self.run_up_m, (int, float))
                                          or not 0.3 <= self.run_up_m <= 10.0):
            raise ValueError(f"run_up_m must be None or a number of metres in [0.3, 10] for an approach (not a "
                             f"drive), got {self.run_up_m!r} with target {self.target!r}")
        scenario.check(self, self.scenario_params)
        if isinstance(self.metrics, str) or not all(isinstance(m, str) for m in self.metrics):
            raise ValueError(f"metrics must be a list of metric names, got {self.metrics!r}")
        object.__setattr__(self, "metrics", tuple(self.metrics))
        unknown = [m for m in (*self.metrics, *scenario.metrics) if m not in METRICS]
        if unknown:
            raise ValueError(f"unknown metric(s) {unknown}; choose from {tuple(METRICS)}")
        if self.estimator_endpoint is not None and not (isinstance(self.estimator_endpoint, str)
                                                        and self.estimator_endpoint.startswith(("tcp://", "ipc://"))):
            raise ValueError(f"estimator_endpoint must be tcp://HOST:PORT or ipc://PATH, got {self.estimator_endpoint!r}")
        on_link = [name for name in attacks if getattr(ATTACKS[name], "on_link", False)]
        if on_link and not (isinstance(self.estimator_endpoint, str) and self.estimator_endpoint.startswith("tcp://")):
            raise ValueError(f"{on_link[0]} attacks the link to a defence service: the episode needs an "
                             f"estimator_endpoint tcp://HOST:PORT (--estimator-endpoint), got {self.estimator_endpoint!r}")
        if self.estimator_keys is not None and (self.estimator_endpoint is None
                                                or not isinstance(self.estimator_keys, str)):
            raise ValueError(f"estimator_keys is a key folder for the link to an estimator_endpoint, got "
                             f"{self.estimator_keys!r} with endpoint {self.estimator_endpoint!r}")
        if not (isinstance(self.estimator_fallback, str) and self.estimator_fallback in ("raw", *ESTIMATORS)):
            raise ValueError(f"estimator_fallback must be 'raw' (the car's own depth, unrepaired) or an estimator "
                             f"{tuple(ESTIMATORS)}, got {self.estimator_fallback!r}")
        if self.estimator_car is not None and (self.estimator_keys is None or not isinstance(self.estimator_car, str)):
            raise ValueError(f"estimator_car names a car of the key folder estimator_keys, got {self.estimator_car!r} "
                             f"with keys {self.estimator_keys!r}")
        if not (isinstance(self.estimator_timeout_ms, (int, float)) and 1.0 <= self.estimator_timeout_ms <= 10_000.0):
            raise ValueError(f"estimator_timeout_ms must be in [1, 10000] ms, got {self.estimator_timeout_ms!r}")
        if not isinstance(self.supervisor, bool):
            raise ValueError(f"supervisor must be true or false, got {self.supervisor!r}")
        if self.control_hz is not None and not 1.0 <= self.control_hz <= 50.0:
            raise ValueError(f"control_hz must be in [1, 50] Hz (the env steps at 50 Hz) or None, "
                             f"got {self.control_hz!r}")

    @property
    def scenario(self):
        """The scenario ``target`` names (a fresh object of its class)."""
        return SCENARIOS[self.target]()

    @property
    def metric_names(self) -> tuple[str, ...]:
        """The metrics this episode scores, in the result row's order: every ``always`` one, the
        spec's and its scenario's."""
        asked = {*self.metrics, *self.scenario.metrics, *(("service",) if self.estimator_endpoint else ()),
                 *(("supervisor",) if self.supervisor else ())}
        chosen = [name for name in METRICS if METRICS[name].always or name in asked]
        return tuple(sorted(chosen, key=lambda name: (METRICS[name].order, name)))

    @property
    def attacks(self) -> tuple[str, ...]:
        return parse_setting(self.setting)[0]

    @property
    def estimator(self) -> str:
        return parse_setting(self.setting)[1]

    @property
    def attack_stable_steps(self) -> int:
        """Env steps (50 Hz) the sign must be visible before an attack may start: by default the
        controller's confirm_frames + 3 of its own steps (slower at a lower ``control_hz``), plus
        the actuation delay, so that a slower or delayed controller still has its track first."""
        if self.stable_steps is not None:
            return self.stable_steps
        every = max(1, round(ENV_HZ / self.control_hz)) if self.control_hz else 1
        return (self.braking.confirm_frames + 3) * every + round(self.delay_ms / 1000.0 * ENV_HZ)

    @property
    def drive(self) -> DriveSpec | None:
        """The drive this spec's seed draws (``target == "drive"``; ``speed`` is the nominal speed)."""
        if self.scenario.target != "drive":
            return None
        return draw_drive(np.random.default_rng(self.seed), *self.drive_s, nominal_speed_mps=self.speed)

    def to_dict(self) -> dict:
        """Every field; the service's two only when the estimator runs in one (so that the form, and the
        id, of an in-process episode stay as they were)."""
        out = asdict(self)
        if self.estimator_endpoint is None:
            del out["estimator_endpoint"], out["estimator_timeout_ms"], out["estimator_fallback"]
        if self.estimator_keys is None:
            del out["estimator_keys"]
        if self.estimator_car is None:
            del out["estimator_car"]
        if not self.supervisor:  # the ids of unsupervised episodes stay as they were
            del out["supervisor"]
        return out

    @classmethod
    def from_dict(cls, raw: dict) -> "TrialSpec":
        """A spec from its :meth:`to_dict` form, read back from JSON (lists back to the tuples and
        configs it holds). Specs written before scenarios were plug-ins held one scenario's parameters as
        three fields of their own (``_LEGACY_SCENARIO``); they read as that scenario."""
        raw = dict(raw)
        raw["braking"] = BrakingConfig(**raw.get("braking", {}))
        for key in ("rho", "t_atk", "drive_s", "metrics"):
            if key in raw:
                raw[key] = tuple(raw[key])
        name, fields = _LEGACY_SCENARIO
        values = {param: raw.pop(field, default) for field, (param, default) in fields.items()}
        if values["cars"]:
            raw["target"], raw["scenario_params"] = name, values
        return cls(**raw)

    @property
    def trial_id(self) -> str:
        """Readable prefix + a hash of the spec, its configs, the code version and the source of
        every plug-in it uses (read now: an edited plug-in makes new ids)."""
        from racf.sim.env.config import EnvConfig

        spec = self.to_dict()
        if spec.pop("estimator_endpoint", None) is not None:  # which service ran it, not where it listened
            spec["estimator_service"] = True
        if spec.pop("estimator_keys", None) is not None:  # an authenticated link, whoever holds the keys
            spec["estimator_curve"] = True
        spec.pop("estimator_car", None)
        payload = {"spec": spec, "env": asdict(EnvConfig()), "code": code_version(*EPISODE_CODE)}
        extra = plugin_sources(self)
        if extra:  # racf's own parts add nothing: the ids of built-in episodes stay as they were
            payload["plugins"] = extra
        digest = hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()[:12]
        return f"{self.label}_{self.target}{self.sign}_v{self.speed:.2f}_seed{self.seed}_{digest}"

    @property
    def label(self) -> str:
        """The setting as reports name it: with ``+supervisor`` when the supervisor runs over the defence."""
        return f"{self.setting}+supervisor" if self.supervisor else self.setting


#: What "the code" of an episode is: the source that runs it and the assets (map, shipped
#: checkpoints). Summaries, tables and the CLI are left out: changing them changes no episode.
EPISODE_CODE = ("racf.sim", "racf.controllers", "racf.odca", "racf.experiments.episode", "racf.experiments.car",
                "racf.experiments.link", "racf.experiments.scenarios",
                "racf.experiments.metrics", "racf.assets", "racf.vehicle")


def plugin_sources(spec: TrialSpec) -> dict[str, str]:
    """What versions a spec's plug-ins and option files: ``{"estimator:NAME": hash, ...}`` for each
    part from outside racf, and each estimator option naming a file or folder (a checkpoint)."""
    from racf.controllers.detectors import DETECTORS
    from racf.provenance import source_version

    parts = [("estimator", ESTIMATORS, spec.estimator), ("detector", DETECTORS, spec.detector),
             ("scenario", SCENARIOS, spec.target), *(("metric", METRICS, name) for name in spec.metric_names),
             *(("attack", ATTACKS, name) for name in spec.attacks)]
    out = {}
    for kind, registry, name in parts:
        source = registry.source_id(name)
        if source is not None:
            out[f"{kind}:{name}"] = source
    for key, value in sorted(spec.estimator_options.items()):
        if isinstance(value, str) and value and os.path.exists(value):
            out[f"option:{key}"] = source_version(os.path.abspath(value))
    return out


def _check_declared_targets(spec: TrialSpec, attacks) -> None:
    """An attack that aims at a kind of declared target (``AttackWrapper.acts_on``) needs the
    scenario's world to declare one (``WorldManager.targets()``): checked here, before any simulator."""
    wanted = {name: ATTACKS[name].acts_on for name in attacks if getattr(ATTACKS[name], "acts_on", None)}
    if not wanted:
        return
    declared = {t.kind for manager in spec.scenario.world(spec, spec.scenario_params) for t in manager.targets()}
    for name, kind in wanted.items():
        if kind not in declared:
            raise ValueError(f"attack {name!r} acts on a {kind} that the scenario's world declares; scenario "
                             f"{spec.target!r} declares {sorted(declared) or 'none'} (a world manager declares its "
                             "bodies in targets(); racf's lead_vehicle declares a vehicle)")
