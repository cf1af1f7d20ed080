"""Sweep specs: a grid or random draws over the attack and the defence, read from TOML.

Example (``experiments/sweeps/specs/smoke.toml``, with every optional field added)::

    name = "smoke"
    mode = "grid"            # every combination, `repeats` seeds each; or "random": `n` draws
    repeats = 1
    seed = 0
    sensor_profile = "qcar2" # the car's sensors as delivered (default), or "ideal" (an ablation)
    sign_geometry = "plate"  # the LiDAR's scan plane meets the sign's plate (default), or "pole"
    detector = "classical"   # the car's stop-sign detector: "classical" (default) or "learned"
    target = "parked_car"    # the scenario (racf.plugins.SCENARIOS; default "sign", the plain approach)
    metrics = ["my_metric"]  # metrics to score beyond those every episode has (default none)

    [space]
    attack = ["patch_occlusion", "none"]       # "none", an attack, or attacks joined by "+"
    estimator = ["raw", "odca"]
    rho = [1.0]                      # grid: values; random: [low, high] drawn uniformly
    t_atk = [2.0]
    speed = [1.5]
    sign = [1, 0]

    [params.stealth_ramp]            # optional: an attack's settings, each a list of values
    rate_mps = [0.3, 1.0, 3.0]       # grid: every combination; random: one drawn per episode

    [estimators.odca]                # optional: an estimator's options (one value each)
    checkpoint = "outputs/odca-head" # a trained head instead of the shipped one

    [scenario.parked_car]            # optional: the parameters `target`'s scenario declares, each a
    ahead_m = [0.5, 1.5]             # list of values; grid: every combination; random: crossed with each draw

A scenario may also take a table of its own name at the top (``Scenario.table``): it lists its
parameters (a value or a list each), and its ``control`` values stand for the plain approach, so a
list holding one (``cars = [0, 1]`` in a table of cars) runs each episode without and with it, on the
same seed (the scenario kit's page has one).

Attacks: any in ``racf.sim.attacks.ATTACKS`` (``patch_occlusion``, ``lidar_spoof``, ...) and
``+``-combinations of them; estimators: any in ``racf.experiments.car.estimators.ESTIMATORS``
(``raw``, ``odca``, ``ekf``, ``chronos``), plug-ins included. An episode's seed depends on its cell and repeat but not on the
estimator or the attack's ``[params]``, so estimators (and the settings of an attack) meet
identical episodes (paired comparisons); so do the values of a scenario's own table. Everything is
checked, with an error naming the field and what is allowed, before any episode runs.

The same fields come as command-line flags (``racf sweep --mode random --n 50 --attack patch_occlusion
--estimator raw odca --rho 0.9 1``), alone or replacing a spec's (:func:`spec_text`).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import tomllib
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from racf.controllers.detectors import DETECTORS
from racf.plugins import METRICS, SCENARIOS
from racf.experiments.episode import TrialSpec
from racf.experiments.link.wire import DEFAULT_TIMEOUT_MS
from racf.experiments.car.estimators import ESTIMATORS, check_options, make_estimator
from racf.experiments.episode.spec import setting_name
from racf.experiments.sweeps.scenario_tables import check_tables, scenario_tables, situations
from racf.sim.attacks import ATTACKS
from racf.sim.env.config import SENSOR_PROFILES
from racf.sim.world.stop_signs import SIGN_GEOMETRIES

__all__ = ["SweepSpec", "load_spec", "parse_spec", "spec_text", "spec_path", "SPACE_KEYS", "SPECS_DIR"]

#: The axes a sweep may vary, and their allowed ranges (None: a list of names).
SPACE_KEYS = {"attack": None, "estimator": None, "rho": (0.0, 1.0), "t_atk": (0.0, 60.0), "speed": (0.1, 3.0),
              "sign": (0, 3)}
_DEFAULTS = {"attack": ["patch_occlusion"], "estimator": ["raw"], "rho": [0.95], "t_atk": [1.75], "speed": [1.5],
             "sign": [0, 1, 2, 3]}
_TOP_KEYS = {"name", "mode", "repeats", "n", "seed", "space", "params", "estimators", "log_steps", "sensor_profile",
             "sign_geometry", "detector", "target", "scenario", "metrics", "estimator_endpoint",
             "estimator_timeout_ms", "estimator_keys", "estimator_car", "supervisor", "estimator_fallback"}


#: The example specs shipped with the project.
SPECS_DIR = Path(__file__).resolve().parent / "specs"


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep (see the module docstring for the fields)."""

    name: str
    mode: str = "grid"
    repeats: int = 1
    n: int = 0
    seed: int = 0
    space: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    log_steps: bool = False
    sensor_profile: str = "qcar2"
    sign_geometry: str = "plate"
    detector: str = "classical"
    estimators: dict = field(default_factory=dict)
    tables: dict = field(default_factory=dict)
    target: str = "sign"
    scenario: dict = field(default_factory=dict)
    metrics: list = field(default_factory=list)
    estimator_endpoint: str | None = None
    estimator_timeout_ms: float = DEFAULT_TIMEOUT_MS
    estimator_keys: str | None = None
    estimator_car: str | None = None
    estimator_fallback: str = "odca"
    #: Each defence alone (False) and/or under the supervisor (True), paired on the same seeds.
    supervisor: tuple = (False,)

    def __post_init__(self) -> None:
        if (not isinstance(self.supervisor, (list, tuple)) or not self.supervisor
                or not all(isinstance(v, bool) for v in self.supervisor)):
            raise ValueError(f"supervisor must be a non-empty list of true/false, got {self.supervisor!r}")
        object.__setattr__(self, "supervisor", tuple(dict.fromkeys(self.supervisor)))
        if self.detector not in DETECTORS:
            raise ValueError(f"detector must be one of {tuple(DETECTORS)}, got {self.detector!r}")
        if self.sensor_profile not in SENSOR_PROFILES:
            raise ValueError(f"sensor_profile must be one of {tuple(SENSOR_PROFILES)}, got {self.sensor_profile!r}")
        if self.sign_geometry not in SIGN_GEOMETRIES:
            raise ValueError(f"sign_geometry must be one of {tuple(SIGN_GEOMETRIES)}, got {self.sign_geometry!r}")
        if self.mode not in ("grid", "random"):
            raise ValueError(f"mode must be 'grid' or 'random', got {self.mode!r}")
        if not (isinstance(self.repeats, int) and self.repeats >= 1):
            raise ValueError(f"repeats must be an int >= 1, got {self.repeats!r}")
        if self.mode == "random" and not (isinstance(self.n, int) and self.n >= 1):
            raise ValueError(f"n (the number of random draws) must be an int >= 1 in random mode, got {self.n!r}")
        if not isinstance(self.seed, int):
            raise ValueError(f"seed must be an int, got {self.seed!r}")
        # A random sweep draws from [low, high]: an axis it does not name stays at the default value.
        defaults = {k: (v * 2 if self.mode == "random" and k in ("rho", "t_atk", "speed") else v)
                    for k, v in _DEFAULTS.items()}
        space = {**defaults, **self.space}
        unknown = sorted(set(self.space) - set(SPACE_KEYS))
        if unknown:
            raise ValueError(f"unknown parameter(s) {unknown} in [space]; allowed: {sorted(SPACE_KEYS)}")
        for key, values in space.items():
            if not isinstance(values, list) or not values:
                raise ValueError(f"space.{key} must be a non-empty list, got {values!r}")
        for value in space["attack"]:
            _attacks(value)
        bad = [e for e in space["estimator"] if e not in ESTIMATORS]
        if bad:
            raise ValueError(f"space.estimator has {bad}; allowed: {tuple(ESTIMATORS)}")
        for key in ("rho", "t_atk", "speed", "sign"):
            lo, hi = SPACE_KEYS[key]
            vals = space[key]
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
                raise ValueError(f"space.{key} must hold numbers, got {vals!r}")
            if not all(lo <= v <= hi for v in vals):
                raise ValueError(f"space.{key} must lie in [{lo}, {hi}], got {vals!r}")
            if key == "sign" and not all(float(v).is_integer() for v in vals):
                raise ValueError(f"space.sign must hold stop-sign indices 0-3, got {vals!r}")
            if self.mode == "random" and key in ("rho", "t_atk", "speed") and len(vals) != 2:
                raise ValueError(f"space.{key} must be [low, high] in random mode, got {vals!r}")
        object.__setattr__(self, "space", space)
        self._check_tables()
        self._check_scenario()
        if not isinstance(self.metrics, list) or any(m not in METRICS for m in self.metrics):
            raise ValueError(f"metrics must be a list of metric names from {tuple(METRICS)}, got {self.metrics!r}")
        self._check_params()
        self._check_estimators()

    def _check_tables(self) -> None:
        check_tables(self.tables, self.target)

    def _situations(self) -> list[tuple[str, dict]]:
        """(scenario, its parameters) of every episode of a cell (``scenario_tables.situations``)."""
        return situations(self.target, self._scenario_combos(), self.tables)

    def _check_scenario(self) -> None:
        """``target`` names a scenario; ``[scenario.<target>]`` gives lists of its parameters' values."""
        if self.target not in SCENARIOS:
            raise ValueError(f"target must be a scenario, one of {tuple(SCENARIOS)}, got {self.target!r}")
        if not isinstance(self.scenario, dict) or any(not isinstance(v, dict) for v in self.scenario.values()):
            raise ValueError("scenario must hold tables: [scenario.NAME] with lists of parameter values")
        other = sorted(set(self.scenario) - {self.target})
        if other:
            raise ValueError(f"[scenario.{other[0]}] names a scenario the sweep does not run (target = {self.target!r})")
        scenario = SCENARIOS[self.target]
        for name, values in self.scenario.get(self.target, {}).items():
            param = scenario.param(name)
            if not isinstance(values, list) or not values:
                raise ValueError(f"scenario.{self.target}.{name} must be a non-empty list of values, got {values!r}")
            for value in values:
                param.check(value, self.target)

    def _scenario_combos(self) -> list[dict]:
        table = self.scenario.get(self.target, {})
        return [dict(zip(table, combo)) for combo in itertools.product(*table.values())]

    def _check_estimators(self) -> None:
        if not isinstance(self.estimators, dict):
            raise ValueError("estimators must be a table of [estimators.<name>] tables")
        for name, options in self.estimators.items():
            if name not in self.space["estimator"]:
                raise ValueError(f"estimators.{name}: {name!r} is not in space.estimator {self.space['estimator']}")
            if not isinstance(options, dict):
                raise ValueError(f"estimators.{name} must be a table of option = value")
            try:
                check_options(name, options)
                make_estimator(name, options)  # a missing or corrupt checkpoint fails before any episode
            except ValueError as err:
                raise ValueError(f"estimators.{name}: {err}") from None

    def _check_params(self) -> None:
        if not isinstance(self.params, dict):
            raise ValueError("params must be a table of [params.<attack>] tables")
        used = {part for value in self.space["attack"] for part in _attacks(value)}
        for name, table in self.params.items():
            if name not in used:
                raise ValueError(f"params.{name}: no attack of space.attack {self.space['attack']} is {name!r}")
            if not isinstance(table, dict) or not table:
                raise ValueError(f"params.{name} must be a table of parameter = [values]")
            for key, values in table.items():
                if not isinstance(values, list) or not values:
                    raise ValueError(f"params.{name}.{key} must be a non-empty list of values, got {values!r}")
                for value in values:  # each value checked by the attack itself, before any episode
                    ATTACKS[name].check_params({key: value})

    def _param_combos(self, attack: str) -> list[dict]:
        """Every combination of the ``[params]`` of the attacks in ``attack`` ([{}] without any)."""
        axes = [(name, key, values) for name in _attacks(attack) for key, values in
                sorted(self.params.get(name, {}).items())]
        combos = []
        for picked in itertools.product(*(values for _, _, values in axes)):
            combo: dict = {}
            for (name, key, _), value in zip(axes, picked):
                combo.setdefault(name, {})[key] = value
            combos.append(combo)
        return combos

    @property
    def spec_hash(self) -> str:
        raw = json.dumps({k: getattr(self, k) for k in ("name", "mode", "repeats", "n", "seed", "space",
                                                        "sensor_profile", "sign_geometry")}
                         | ({"params": self.params} if self.params else {})
                         | ({"estimators": self.estimators} if self.estimators else {})
                         | ({"detector": self.detector} if self.detector != "classical" else {})
                         | self.tables
                         | ({"target": self.target} if self.target != "sign" else {})
                         | ({"scenario": self.scenario} if self.scenario else {})
                         | ({"metrics": self.metrics} if self.metrics else {})
                         | ({"supervisor": list(self.supervisor)} if self.supervisor != (False,) else {}), sort_keys=True)
        return hashlib.sha256(raw.encode()).hexdigest()[:12]

    def episodes(self) -> list[TrialSpec]:
        """The sweep's episodes, in a fixed order."""
        s = self.space
        out = []
        if self.mode == "grid":
            cells = itertools.product(s["attack"], s["rho"], s["t_atk"], s["speed"], s["sign"])
            for cell in cells:
                for repeat in range(self.repeats):
                    seed = self._episode_seed(cell, repeat)
                    for params in self._param_combos(cell[0]):
                        for target, situation in self._situations():
                            for estimator in s["estimator"]:
                                for supervised in self.supervisor:
                                    out.append(_trial(cell, estimator, seed, self, params, target, situation,
                                                      supervised))
        else:
            rng = np.random.default_rng(self.seed)
            for i in range(self.n):
                cell = (s["attack"][rng.integers(len(s["attack"]))], round(float(rng.uniform(*s["rho"])), 4),
                        round(float(rng.uniform(*s["t_atk"])), 3), round(float(rng.uniform(*s["speed"])), 3),
                        int(s["sign"][rng.integers(len(s["sign"]))]))
                seed = self._episode_seed(cell, i)
                combos = self._param_combos(cell[0])
                params = combos[rng.integers(len(combos))] if len(combos) > 1 else combos[0]
                for target, situation in self._situations():
                    for estimator in s["estimator"]:
                        for supervised in self.supervisor:
                            out.append(_trial(cell, estimator, seed, self, params, target, situation, supervised))
        return out

    def _episode_seed(self, cell: tuple, repeat: int) -> int:
        return int(self.seed * 1_000_003 + zlib.crc32(json.dumps([*cell, repeat]).encode()) % 1_000_000)


def _attacks(value) -> tuple[str, ...]:
    if not isinstance(value, str) or not value:
        raise ValueError(f"space.attack entries must be strings like 'patch_occlusion' or 'patch_occlusion+lidar_spoof', got {value!r}")
    if value == "none":
        return ()
    parts = tuple(value.split("+"))
    bad = [p for p in parts if p not in ATTACKS]
    if bad:
        raise ValueError(f"space.attack {value!r} has unknown attack(s) {bad}; allowed: 'none' or "
                         f"'+'-joined {tuple(ATTACKS)}")
    return parts


def _trial(cell: tuple, estimator: str, seed: int, sweep: SweepSpec, params: dict | None = None,
           target: str | None = None, situation: dict | None = None, supervisor: bool = False) -> TrialSpec:
    attack, rho, t_atk, speed, sign = cell
    return TrialSpec(setting_name(_attacks(attack), estimator), int(sign), float(speed), seed,
                     rho=(float(rho), float(rho)), t_atk=(float(t_atk), float(t_atk)),
                     sensor_profile=sweep.sensor_profile, sign_geometry=sweep.sign_geometry,
                     attack_params=params or {}, detector=sweep.detector,
                     estimator_options=sweep.estimators.get(estimator, {}), metrics=tuple(sweep.metrics),
                     estimator_endpoint=sweep.estimator_endpoint, estimator_timeout_ms=sweep.estimator_timeout_ms,
                     estimator_keys=sweep.estimator_keys, estimator_car=sweep.estimator_car, estimator_fallback=sweep.estimator_fallback,
                     target=target or sweep.target, scenario_params=situation or {}, supervisor=supervisor)


def spec_path(path: str | Path) -> Path:
    """The spec file: ``path`` itself, or a shipped spec of that name."""
    path = Path(path)
    if path.is_file():
        return path
    if (SPECS_DIR / path.name).is_file():
        return SPECS_DIR / path.name
    raise ValueError(f"no sweep spec at {path} (shipped specs: {sorted(p.name for p in SPECS_DIR.glob('*.toml'))})")


def load_spec(path: str | Path) -> SweepSpec:
    """Reads and validates a TOML spec; a ValueError names the file, the field and what is allowed."""
    path = spec_path(path)
    return parse_spec(path.read_text(), str(path), default_name=path.stem)


def parse_spec(text: str, source: str = "spec", default_name: str = "sweep") -> SweepSpec:
    """Validates a spec given as TOML text; errors start with ``source``."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{source}: not valid TOML: {err}") from None
    tables = scenario_tables()
    unknown = sorted(set(raw) - _TOP_KEYS - set(tables))
    if unknown:
        raise ValueError(f"{source}: unknown field(s) {unknown}; allowed: {sorted(_TOP_KEYS | set(tables))}")
    if "space" in raw and not isinstance(raw["space"], dict):
        raise ValueError(f"{source}: space must be a table ([space])")
    if not raw.get("space"):
        raise ValueError(f"{source}: the spec has no [space]: name what the sweep varies, at least one of "
                         f"{sorted(SPACE_KEYS)} (e.g. attack = [\"patch_occlusion\"])")
    try:
        spec = SweepSpec(name=str(raw.get("name", default_name)), mode=raw.get("mode", "grid"),
                         repeats=raw.get("repeats", 1), n=raw.get("n", 0), seed=raw.get("seed", 0),
                         space=raw.get("space", {}), params=raw.get("params", {}),
                         log_steps=bool(raw.get("log_steps", False)),
                         sensor_profile=raw.get("sensor_profile", "qcar2"),
                         sign_geometry=raw.get("sign_geometry", "plate"),
                         detector=raw.get("detector", "classical"), estimators=raw.get("estimators", {}),
                         tables={t: raw[t] for t in tables if t in raw}, target=raw.get("target", "sign"),
                         scenario=raw.get("scenario", {}), metrics=raw.get("metrics", []),
                         estimator_endpoint=raw.get("estimator_endpoint"),
                         estimator_timeout_ms=raw.get("estimator_timeout_ms", DEFAULT_TIMEOUT_MS),
                         estimator_keys=raw.get("estimator_keys"), estimator_car=raw.get("estimator_car"),
                         estimator_fallback=raw.get("estimator_fallback", "odca"),
                         supervisor=raw.get("supervisor", (False,)))
        episodes = spec.episodes()
    except ValueError as err:
        raise ValueError(f"{source}: {err}") from None
    if not episodes:
        raise ValueError(f"{source}: the sweep has no episodes")
    return spec


def spec_text(path: str | Path | None = None, fields: dict | None = None, space: dict | None = None) -> str:
    """The TOML text of a sweep: the spec at ``path`` (or an empty one) with top-level
    ``fields`` and ``[space]`` axes replaced by the given ones (command-line flags).

    Unless ``fields`` names it, a changed sweep is named after its content (``smoke-1a2b3c4d``),
    so that it does not share a results folder with the spec it came from. The text is what
    the results folder keeps.
    """
    import tomli_w

    if path is not None:
        path = spec_path(path)
        try:
            raw = tomllib.loads(path.read_text())
        except tomllib.TOMLDecodeError as err:
            raise ValueError(f"{path}: not valid TOML: {err}") from None
    else:
        raw = {}
    fields, space = fields or {}, space or {}
    if not (fields or space):
        return path.read_text() if path is not None else tomli_w.dumps(raw)
    if not isinstance(raw.get("space", {}), dict):
        raise ValueError(f"{path}: space must be a table ([space])")
    estimators = {**raw.get("estimators", {})}
    for name, options in fields.get("estimators", {}).items():  # an option given replaces that option only
        estimators[name] = {**estimators.get(name, {}), **options}
    raw.update(fields)
    if estimators:
        raw["estimators"] = estimators
    if space:
        raw["space"] = {**raw.get("space", {}), **space}
    if "name" not in fields:
        digest = hashlib.sha256(json.dumps(raw, sort_keys=True).encode()).hexdigest()[:8]
        base = raw.get("name", path.stem if path is not None else "sweep")
        raw = {**raw, "name": f"{base}-{digest}"}
    return tomli_w.dumps(raw)
