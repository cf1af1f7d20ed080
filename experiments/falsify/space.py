"""The space a falsifying search explores: the scenario and the attacks' settings, read from TOML.

Example (``experiments/falsify/spaces/default.toml``, the space ``racf falsify`` uses unless told)::

    [scenario]
    sign = [0, 1, 2, 3]                          # a list: one of these values
    speed = {low = 1.0, high = 2.0}              # a range: uniform (int = true: integers)
    run_up_m = {low = 1.2, high = 3.0}           # where the car starts before the line
    stable_steps = {low = 5, high = 60, int = true}  # when the attack may start after first sight

    [attack.dropout_timed]                       # an attack's settable parameters
    scans = {low = 1, high = 8, int = true}
    effect = ["blackout", "bias"]
    bias_m = {low = 0.2, high = 1.5}

Only the sections of the attacks a search runs are used; a parameter a section leaves out keeps the
attack's default. ``patch_occlusion``'s ``rho`` and ``t_atk`` are the episode's own fields (one
value each: a point, not a range). A trial's episode seed is not searched: it comes from what the
evaluation is (the search's seed and the trial's number), so every sampler meets the same noise at
the same step of its budget.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from racf.experiments.episode.plan import longest_run_up
from racf.plugins import SCENARIOS
from racf.experiments.episode.spec import TARGETS, TrialSpec, setting_name
from racf.sim.attacks import ATTACKS

__all__ = ["SearchSpace", "Dimension", "DEFAULT_SPACE", "SCENARIO_FIELDS", "load_space"]

#: The shipped space.
DEFAULT_SPACE = Path(__file__).with_name("spaces") / "default.toml"
#: Scenario fields a space may search (``TrialSpec`` fields).
SCENARIO_FIELDS = ("sign", "speed", "run_up_m", "stable_steps", "supervisor", "t_atk")
#: The patch's parameters that are the episode's own fields.
_PATCH_FIELDS = ("rho", "t_atk")


@dataclass(frozen=True)
class Dimension:
    """One searched parameter: a choice among ``choices``, or a uniform range [low, high]."""

    name: str
    choices: tuple | None = None
    low: float | None = None
    high: float | None = None
    integer: bool = False

    @classmethod
    def parse(cls, name: str, raw: Any) -> "Dimension":
        if isinstance(raw, list):
            if not raw or len({type(v) for v in raw}) != 1 or not all(isinstance(v, (str, int, float, bool))
                                                                       for v in raw):
                raise ValueError(f"{name}: a list of choices must be non-empty and of one scalar type, got {raw!r}")
            return cls(name, choices=tuple(raw))
        if isinstance(raw, dict):
            extra = sorted(set(raw) - {"low", "high", "int"})
            low, high = raw.get("low"), raw.get("high")
            if extra or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (low, high)) \
                    or not low < high:
                raise ValueError(f"{name}: a range is {{low = A, high = B}} with A < B (and optionally int = true), "
                                 f"got {raw!r}")
            integer = bool(raw.get("int", False))
            if integer and not (float(low).is_integer() and float(high).is_integer()):
                raise ValueError(f"{name}: an integer range needs integer bounds, got {raw!r}")
            return cls(name, low=float(low), high=float(high), integer=integer)
        raise ValueError(f"{name}: give a list of choices or a range {{low = A, high = B}}, got {raw!r}")

    def suggest(self, trial) -> Any:
        """The value an Optuna trial suggests for this dimension."""
        if self.choices is not None:
            return trial.suggest_categorical(self.name, list(self.choices))
        if self.integer:
            return trial.suggest_int(self.name, int(self.low), int(self.high))
        return trial.suggest_float(self.name, self.low, self.high)

    def cast(self, value: Any) -> Any:
        """A value of this dimension as the episode takes it (stored trials may hold 3.0 for 3)."""
        return int(round(value)) if self.integer else value

    def bounds(self) -> tuple:
        """The values at this dimension's edges: every choice, or a range's two ends."""
        return self.choices if self.choices is not None else (self.cast(self.low), self.cast(self.high))

    def to_json(self) -> dict:
        if self.choices is not None:
            return {"choices": list(self.choices)}
        return {"low": self.low, "high": self.high, "int": self.integer}


@dataclass(frozen=True)
class SearchSpace:
    """What a search varies, for one defence and one set of attacks.

    Attributes:
        defence: the estimator under test.
        attacks: the attacks every episode runs.
        dimensions: the searched parameters (``sign``, ``attack.dropout_timed.scans``, ...).
        fixed: ``TrialSpec`` fields every episode shares (sensor profile, detector, ...).
    """

    defence: str
    attacks: tuple[str, ...]
    dimensions: tuple[Dimension, ...]
    fixed: tuple[tuple[str, Any], ...] = ()

    @property
    def setting(self) -> str:
        return setting_name(self.attacks, self.defence)

    def suggest(self, trial) -> dict:
        """The parameters of one trial (Optuna's ask)."""
        return {d.name: d.suggest(trial) for d in self.dimensions}

    def trial_spec(self, params: dict, seed: int) -> TrialSpec:
        """The episode of one point of the space (a ValueError names a value the episode refuses)."""
        fields: dict[str, Any] = dict(self.fixed)
        attack_params: dict[str, dict] = {}
        dims = {d.name: d for d in self.dimensions}
        for name, value in params.items():
            value = dims[name].cast(value) if name in dims else value
            if name.startswith("scenario."):  # a parameter the scenario declares
                fields.setdefault("scenario_params", {})[name.split(".", 2)[2]] = value
            elif name.startswith("attack."):
                _, attack, key = name.split(".", 2)
                if attack == "patch_occlusion" and key in _PATCH_FIELDS:
                    fields[key] = (float(value), float(value))
                else:
                    attack_params.setdefault(attack, {})[key] = value
            else:
                fields[name] = value
        sign = int(fields.pop("sign", 0))
        if fields.get("run_up_m") is not None:  # no longer than the sign's lane allows
            kind = SCENARIOS[fields.get("target", "sign")].target
            longest = longest_run_up(kind, sign, fields.get("sign_geometry", "plate"))
            fields["run_up_m"] = min(float(fields["run_up_m"]), math.floor(longest * 1e6) / 1e6)
        return TrialSpec(self.setting, speed=float(fields.pop("speed", 1.5)), sign=sign, seed=int(seed),
                         attack_params=attack_params, **fields)

    def extremes(self) -> list[TrialSpec]:
        """An episode at each bound of each dimension, the others at their first bound: a value the
        episode refuses anywhere in the space is refused at one of these, before any draw.

        Raises ValueError naming the dimension and the value the episode refuses."""
        first = {d.name: d.bounds()[0] for d in self.dimensions}
        specs = []
        for d in self.dimensions:
            for value in d.bounds():
                try:
                    specs.append(self.trial_spec({**first, d.name: value}, 0))
                except ValueError as err:
                    raise ValueError(f"the space's {d.name} = {value!r} is out of what the episode takes: {err}") from None
        return specs

    def to_json(self) -> dict:
        return {"defence": self.defence, "attacks": list(self.attacks),
                "dimensions": {d.name: d.to_json() for d in self.dimensions}, "fixed": dict(self.fixed)}


def load_space(defence: str, attacks: tuple[str, ...], path: str | Path | None = None,
               fixed: dict | None = None) -> SearchSpace:
    """The space for ``defence`` under ``attacks`` from a TOML file (default the shipped one).

    Raises ValueError naming what is wrong (an unknown field or attack, a parameter the attack does
    not take, a bad range) before anything runs."""
    path = Path(path) if path is not None else DEFAULT_SPACE
    try:
        raw = tomllib.loads(path.read_text())
    except OSError as err:
        raise ValueError(f"cannot read the space {path}: {err.strerror or err}") from None
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"the space {path} is not valid TOML: {err}") from None
    unknown = sorted(set(raw) - {"scenario", "attack"})
    if unknown:
        raise ValueError(f"the space {path} has unknown section(s) {unknown}; allowed: [scenario], [attack.NAME]")
    if not attacks:
        raise ValueError("a falsifying search needs at least one attack")
    unknown = [a for a in attacks if a not in ATTACKS]
    if unknown:
        raise ValueError(f"unknown attack(s) {unknown}; choose from {list(ATTACKS)}")
    scenario = dict(raw.get("scenario", {}))
    target = scenario.pop("target", (fixed or {}).get("target", "sign"))
    if target not in SCENARIOS:
        raise ValueError(f"[scenario] target of {path} must be a scenario, one of {list(SCENARIOS)}, got {target!r}")
    # [scenario.NAME]: the parameters a scenario declares (a field such as sign = {low, high} is a range).
    tables = {k: scenario.pop(k) for k in list(scenario)
              if k not in SCENARIO_FIELDS and k in SCENARIOS and isinstance(scenario[k], dict)}
    if set(tables) - {target}:
        raise ValueError(f"[scenario.{sorted(set(tables) - {target})[0]}] of {path} names a scenario the search "
                         f"does not run (target = {target!r})")
    for key in tables.get(target, {}):
        SCENARIOS[target].param(key)  # a parameter the scenario does not declare is an error now
    fixed = {**(fixed or {}), **({"target": target} if target != "sign" else {})}
    bad = sorted(set(scenario) - set(SCENARIO_FIELDS))
    if bad:
        raise ValueError(f"[scenario] of {path} names {bad}; it may search {list(SCENARIO_FIELDS)}")
    dims = [Dimension.parse(name, value) for name, value in scenario.items()]
    dims += [Dimension.parse(f"scenario.{target}.{key}", value) for key, value in tables.get(target, {}).items()]
    sections = raw.get("attack", {})
    bad = sorted(set(sections) - set(ATTACKS))
    if bad:
        raise ValueError(f"[attack] of {path} names unknown attack(s) {bad}; choose from {list(ATTACKS)}")
    for attack in attacks:
        table = sections.get(attack, {})
        allowed = set(ATTACKS[attack].settable_params()) | (set(_PATCH_FIELDS) if attack == "patch_occlusion" else set())
        bad = sorted(set(table) - allowed)
        if bad:
            raise ValueError(f"[attack.{attack}] of {path} names {bad}; {attack} takes {sorted(allowed)}")
        dims += [Dimension.parse(f"attack.{attack}.{key}", value) for key, value in table.items()]
    space = SearchSpace(defence, tuple(attacks), tuple(dims), tuple(sorted((fixed or {}).items())))
    space.setting  # an unknown defence or attack is an error now, not at the first trial
    if "sign" in scenario:
        signs = Dimension.parse("sign", scenario["sign"])
        values = signs.choices if signs.choices is not None else (signs.low, signs.high)
        count = TARGETS[SCENARIOS[target].target]
        if not all(0 <= int(v) < count for v in values):
            raise ValueError(f"[scenario] sign must lie in 0..{count - 1}, got {scenario['sign']!r}")
    return space
