"""What a scenario is: the situation an episode puts the car in, declared once.

A scenario declares its parameters (:class:`Param`: type, range, default, unit and meaning);
``TrialSpec.scenario_params``, the CLI's ``--scenario-param``, a sweep spec's
``[scenario.<name>]`` table, a falsification space and ``racf list`` all read that one
declaration. It plans the episode: pure, from the spec and the map to the env's settings, its
world (managers the env runs without knowing them, each logging its own ground-truth columns:
``racf.sim.world.manager``), its reset options and the car's mission. It owns how the episode is
judged: its criteria (:attr:`Scenario.criteria`, ``racf.experiments.episode.criteria``), the
metrics it asks for (:attr:`Scenario.metrics`) and when its episode is over (:meth:`Scenario.over`).

A scenario registers under the entry-point group ``racf.scenarios`` (or is loaded with
``--plugin FILE.py``), racf's own the same way as a user's; ``TrialSpec.target`` names it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from racf.controllers import Phase
from racf.experiments.episode.criteria import TARGET_CRITERIA, Criterion
from racf.experiments.episode.spec import TARGETS
from racf.sim.world.manager import WorldManager

if TYPE_CHECKING:  # the plan is made by racf.experiments.episode, which reads scenarios
    from racf.experiments.episode.plan import EpisodePlan

__all__ = ["Param", "Scenario", "TARGET_KINDS", "RUN_THROUGH_M", "params_label"]

#: What a route is built around, and how many of each the map holds (``TrialSpec.sign`` indexes them).
TARGET_KINDS = TARGETS
#: By default an episode ends once the bumper is this far past the last target's line, m.
RUN_THROUGH_M = 0.5


def params_label(values: dict[str, Any]) -> str:
    """``case=removed, shift_m=1.0``: a scenario's parameter values as results, failure lines and card
    names write them ('' for none)."""
    return ", ".join(f"{name}={value}" for name, value in values.items())


@dataclass(frozen=True)
class Param:
    """One parameter of a scenario.

    Attributes:
        name: its key (an identifier).
        default: its value when not given; its type is the parameter's (int, float, bool or str).
        low, high: the range of a number (inclusive).
        choices: the values a str (or any) parameter may take.
        unit: what a number counts (``m``, ``s``, ``m/s``, ``cars``).
        meaning: one line for ``racf list`` and the docs.
    """

    name: str
    default: Any
    low: float | None = None
    high: float | None = None
    choices: tuple | None = None
    unit: str = ""
    meaning: str = ""

    @property
    def type(self) -> type:
        return type(self.default)

    def check(self, value: Any, owner: str) -> Any:
        """The value as the parameter's type; ValueError names the scenario, the parameter and what is allowed."""
        kind = self.type
        if kind is bool or kind not in (int, float):
            ok = isinstance(value, kind)
        else:  # a number: an int parameter takes only whole values
            ok = (isinstance(value, (int, float)) and not isinstance(value, bool)
                  and (kind is float or float(value).is_integer()))
        if ok and kind in (int, float):
            value = kind(value)
            ok = (math.isfinite(value) and (self.low is None or value >= self.low)
                  and (self.high is None or value <= self.high))
        if ok and self.choices is not None:
            ok = value in self.choices
        if not ok:
            raise ValueError(f"scenario {owner!r} parameter {self.name!r} must be {self.allowed()}, got {value!r}")
        return value

    def allowed(self) -> str:
        if self.choices is not None:
            return f"one of {list(self.choices)}"
        kind = self.type.__name__
        if self.low is not None or self.high is not None:
            unit = f" {self.unit}" if self.unit else ""
            return f"{'an' if kind == 'int' else 'a'} {kind} in [{self.low}, {self.high}]{unit}"
        return f"a {kind}"

    def describe(self) -> str:
        """``name (range, default): meaning`` for listings."""
        return f"{self.name} ({self.allowed()}, default {self.default!r}): {self.meaning}"


class Scenario:
    """A situation. Subclass it, set the class attributes, and override what the situation changes.

    Attributes:
        name: its key (``TrialSpec.target``, ``--target``, a sweep's ``target``).
        meaning: one line for ``racf list``.
        target: what the route is built around (``TARGET_KINDS``: ``sign``, ``obstacle`` or ``drive``);
            the attacks that can act on it are those whose ``targets`` list it.
        params: the scenario's parameters.
        metrics: what the referee scores beyond the metrics every episode has (``racf.metrics``).
        criteria: the rules its episodes are judged by (``Criterion`` classes; by default the stop
            rule where a target stands and no needless stop where none does); the ``criteria``
            metric writes each verdict and the driving score.
        aliases: older names of its parameters on the command line, mapped to theirs
            (``{"traffic_cars": "cars"}`` makes ``--traffic-cars N`` run it with ``cars = N``).
        table: a top-level table of a sweep spec that lists its parameters (cross-traffic's
            ``[traffic]``), beside ``[scenario.<name>]``; None: none.
        control: parameter values in that table that stand for the plain approach of its
            ``target`` kind (cross-traffic's ``{"cars": 0}``): the paired control episode.
    """

    name: ClassVar[str] = "scenario"
    #: Marks the base of racf's scenarios for the registries (``racf.plugins.PART_KIND``).
    racf_part: ClassVar[str] = "scenario"
    meaning: ClassVar[str] = ""
    target: ClassVar[str] = "sign"
    params: ClassVar[tuple[Param, ...]] = ()
    metrics: ClassVar[tuple[str, ...]] = ()
    criteria: ClassVar[tuple[type[Criterion], ...]] = TARGET_CRITERIA
    aliases: ClassVar[dict[str, str]] = {}
    table: ClassVar[str | None] = None
    control: ClassVar[dict[str, Any]] = {}

    @classmethod
    def values(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Every parameter's value: ``given``, checked, over the defaults, in declaration order.
        ValueError names an unknown parameter and the declared ones."""
        if not isinstance(given, dict):
            raise ValueError(f"scenario_params must be a dict of parameter -> value, got {given!r}")
        declared = {p.name: p for p in cls.params}
        unknown = sorted(set(given) - set(declared))
        if unknown:
            raise ValueError(f"scenario {cls.name!r} has no parameter(s) {unknown}; its parameters: "
                             f"{list(declared) or 'none'}")
        return {name: param.check(given[name], cls.name) if name in given else param.default
                for name, param in declared.items()}

    @classmethod
    def param(cls, name: str) -> Param:
        for p in cls.params:
            if p.name == name:
                return p
        raise ValueError(f"scenario {cls.name!r} has no parameter {name!r}; its parameters: "
                         f"{[p.name for p in cls.params] or 'none'}")

    def check(self, spec: Any, values: dict[str, Any]) -> None:
        """Refuses (ValueError) a spec this scenario cannot run beyond its parameters' ranges."""

    def run_up(self, spec: Any) -> float | None:
        """The approach's run-up when the spec gives none, m (None: the route's default, 3 m)."""
        return None

    def env_settings(self, spec: Any, values: dict[str, Any]) -> dict[str, Any]:
        """Env settings this scenario needs beyond the spec's sensors and signs."""
        return {}

    def world(self, spec: Any, values: dict[str, Any]) -> tuple[WorldManager, ...]:
        """The world managers the env runs for this scenario (bodies added, moved or hidden)."""
        return ()

    def plan(self, spec: Any, values: dict[str, Any], draft: "EpisodePlan") -> "EpisodePlan":
        """The episode's plan from the route's (``draft``): add reset options, other actors, or
        change the car's mission. Pure: the same spec gives the same plan."""
        return draft

    def over(self, plan: "EpisodePlan", rows: list[dict]) -> bool:
        """Whether the episode is over after the step whose row is ``rows[-1]`` (``rows``: the step log
        so far, the world managers' columns included). By default once the car is done with its last
        target: it stopped there for good (its braker's phase ``done``), or its bumper is
        ``RUN_THROUGH_M`` past the line. A scenario may run on (until a crossing car or a person has
        passed) or stop sooner; the episode's time limit and a criterion that ``terminates`` end it
        anyway."""
        row = rows[-1]
        return row["slot"] == len(plan.mission.targets) - 1 and (
            row["phase"] == Phase.DONE.value or row["dist_to_stop_line"] < -RUN_THROUGH_M)

    def report(self, frame: Any, summary: dict) -> tuple[list[str], dict[str, Any]]:
        """What this scenario adds to a sweep's report, given the sweep's result rows (``frame``, every
        scenario's) and its summaries: Markdown lines after racf's tables, and JSON files by name for the
        results folder (cross-traffic: its collision table and its paired episodes). By default nothing."""
        return [], {}

    @staticmethod
    def replace(plan: "EpisodePlan", **changes: Any) -> "EpisodePlan":
        return dataclasses.replace(plan, **changes)
