"""The scorecard's rows and batteries as types, and the makers of a row's episodes.

:class:`LoopRow` (one closed-loop row: a title, its N and how its episodes are made for a defence) and
:class:`Battery` (a named list of rows) are what ``racf.experiments.scorecard.battery`` releases its
batteries with; the makers here give a row's episodes, the same seeds for every defence (paired).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

from racf.experiments.episode import TrialSpec
from racf.experiments.sweeps.batches import batch_specs
from racf.experiments.sweeps.spec import SweepSpec

__all__ = ["LoopRow", "Battery", "PENALTIES", "CAR_DETECTOR", "paper_row", "sweep_row", "drives_row"]

#: The driving score's penalties (CARLA's leaderboard coefficients): one factor per infraction.
PENALTIES = {"ran_stop_sign": 0.80, "hit_static_object": 0.65, "hit_vehicle": 0.60}


@dataclass(frozen=True)
class LoopRow:
    """One closed-loop row: ``make(defence, n)`` gives its episodes."""

    key: str
    title: str
    n: int
    n_quick: int
    make: Callable[[str, int], list[TrialSpec]] = field(compare=False, repr=False)
    attacked: bool = True
    driving: bool = False  # also a driving score (route completion x penalties), as the drives rows have
    #: The link its defence is served over (``"plain"`` or ``"curve"``): the card starts that
    #: ``racf serve`` itself (``racf.experiments.scorecard.link``); None: as the command says.
    link: str | None = None

    def specs(self, defence: str, quick: bool = False) -> list[TrialSpec]:
        return self.make(defence, self.n_quick if quick else self.n)


#: The car's detector in every battery so far: the classical one, the default when each was
#: released. Pinned here, so that no row follows a later default silently.
CAR_DETECTOR = "classical"


def paper_row(setting: str) -> Callable[[str, int], list[TrialSpec]]:
    def make(defence: str, n: int) -> list[TrialSpec]:
        return batch_specs(setting + ("" if defence == "raw" else f"+{defence}"), n, detector=CAR_DETECTOR)
    return make


def sweep_row(name: str, attack: str, *, mode: str = "random", detector: str = CAR_DETECTOR, params: dict | None = None,
           t_atk: list | None = None, rho: list | None = None, speed: list | None = None, tables: dict | None = None
           ) -> Callable[[str, int], list[TrialSpec]]:
    """Episodes of a sweep over the four signs, the same seeds for every defence (paired): ``n``
    random draws, or (grid) ``n // 4`` repeats at each sign and each of the attack's settings (``tables``:
    a scenario's own sweep tables, ``SweepSpec.tables``)."""
    def make(defence: str, n: int) -> list[TrialSpec]:
        space = {"attack": [attack], "estimator": [defence], "sign": [0, 1, 2, 3]}
        if mode == "random":
            space |= {"rho": rho or [0.9, 1.0], "t_atk": t_atk or [0.5, 3.0], "speed": speed or [1.0, 2.0]}
            spec = SweepSpec(name, mode="random", n=n, seed=0, space=space, params=params or {}, log_steps=True,
                             detector=detector, tables=tables or {})
        else:
            space |= {"rho": rho or [1.0], "t_atk": t_atk or [3.0], "speed": speed or [1.5]}
            spec = SweepSpec(name, mode="grid", repeats=max(1, n // 4), seed=0, space=space, params=params or {},
                             log_steps=True, detector=detector, tables=tables or {})
        return spec.episodes()
    return make


def drives_row(attack: bool) -> Callable[[str, int], list[TrialSpec]]:
    def make(defence: str, n: int) -> list[TrialSpec]:
        setting = ("attack" if attack else "clean") + ("" if defence == "raw" else f"+{defence}")
        return [TrialSpec(setting, 0, 1.5, seed, target="drive", detector=CAR_DETECTOR) for seed in range(n)]
    return make


@dataclass(frozen=True)
class Battery:
    """A named battery: its closed-loop rows, its drives and its offline settings."""

    name: str
    loop: tuple[LoopRow, ...]
    drives: tuple[LoopRow, ...]
    detector: str = CAR_DETECTOR  # the car's detector in its rows (a row's title names any other)
    offline_presets: tuple[str, ...] = ("weak", "mid", "strong")
    offline_split: str = "by_series"
    offline_draws: int = 5
    offline_draws_quick: int = 1

    def rows(self) -> tuple[LoopRow, ...]:
        return self.loop + self.drives

    def quick(self) -> "Battery":
        return replace(self, name=f"{self.name}-quick")

    def in_scenario(self, scenario: str, params: dict | None = None) -> "Battery":
        """The battery with every plain stop-sign approach of its closed-loop rows run in ``scenario``
        instead (``racf.plugins.SCENARIOS``, a scenario whose target is a stop sign), named
        ``NAME@SCENARIO[param=value, ...]`` (so that cards of one scenario with other parameters never
        share a name or a file); cross-traffic rows and the drives stay as they are. ValueError names a
        scenario that does not approach a stop sign, or a parameter it refuses."""
        from racf.experiments.scenarios.base import params_label
        from racf.plugins import SCENARIOS

        if scenario not in SCENARIOS or SCENARIOS[scenario].target != "sign":
            raise ValueError(f"a battery runs in a scenario that approaches a stop sign; choose from "
                             f"{[n for n in SCENARIOS if SCENARIOS[n].target == 'sign']}, got {scenario!r}")
        values = SCENARIOS[scenario].values(params or {})

        def situated(make: Callable[[str, int], list[TrialSpec]]) -> Callable[[str, int], list[TrialSpec]]:
            def remade(defence: str, n: int) -> list[TrialSpec]:
                return [replace(s, target=scenario, scenario_params=values) if s.target == "sign" else s
                        for s in make(defence, n)]
            return remade

        loop = tuple(replace(row, make=situated(row.make)) for row in self.loop)
        label = params_label(values)
        return replace(self, name=f"{self.name}@{scenario}" + (f"[{label}]" if label else ""), loop=loop)
