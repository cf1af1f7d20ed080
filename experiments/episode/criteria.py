"""Criteria: the rules an episode is judged by, owned by its scenario (CARLA's atomic criteria).

A criterion names the rule it checks (``checks``), says whether the rule applies to an episode
(:meth:`Criterion.applies`: no stop rule where no sign stands) and judges the episode's log
(:meth:`Criterion.passed`), with measures of its own (``fields``, :meth:`Criterion.measures`).
Failing may end the episode (``terminates``: the runner asks :meth:`Criterion.fails_at` of each
step's row) and costs the driving score the criterion's ``penalty``: the score is the product of
the failed criteria's penalties (CARLA's leaderboard coefficients: hitting a person x 0.50,
a vehicle x 0.60, a static object x 0.65, running a stop sign x 0.80).

A scenario lists its criteria (``Scenario.criteria``); racf's target approaches judge the stop
rule where a target stands and needless stops where none does (:data:`TARGET_CRITERIA`). The
``criteria`` metric writes each verdict into the result row: ``<name>`` True (passed), False
(failed) or None (the rule does not apply), its fields, and ``driving_score``. Like the metrics,
a criterion reads the log and the plan, never the simulator, so a stored log can be judged again.

Example:
    >>> from racf.experiments.episode.criteria import TARGET_CRITERIA
    >>> [(c.name, c.penalty) for c in TARGET_CRITERIA]
    [('stop_rule', 0.8), ('no_needless_stop', 0.7)]
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

import pandas as pd

from racf.experiments.episode.fields import Field
from racf.experiments.episode.scoring import AT_REST_MPS, TargetOutcome, score_log

if TYPE_CHECKING:  # the runner makes episodes and runs the criteria
    from racf.experiments.episode.runner import Episode

__all__ = ["verdict_line", "Criterion", "StopRule", "NoNeedlessStop", "NoContact", "TARGET_CRITERIA", "standing_outcomes", "NEEDLESS_STOP_PENALTY",
           "STOP_RULE_PENALTY"]

#: CARLA's leaderboard: running a stop sign.
STOP_RULE_PENALTY = 0.80
#: The driving score's factor for a needless stop. CARLA's leaderboard names no such infraction;
#: its nearest is failing to keep the road's minimum speed (x 0.70): a stop in a running lane
#: with nothing to stop for is the rear-end hazard and the delay a phantom attack aims at. It
#: weighs more than running a real sign (x 0.80), as CARLA's minimum-speed penalty does.
NEEDLESS_STOP_PENALTY = 0.70


class Criterion:
    """One rule an episode is judged by. Subclass it, set the class attributes, write :meth:`passed`.

    Attributes:
        name: the result row's verdict column (an identifier, unique among the scenario's criteria).
        checks: what it checks, one line (``racf list``, the docs).
        penalty: the driving score's factor when it fails (1.0: none).
        terminates: failing ends the episode (the runner checks :meth:`fails_at` at each step).
        optional: informative only: it costs no driving score when it fails.
        fields: measures of its own in the result row (``Field``), filled by :meth:`measures`
            where the rule applies, their defaults where it does not.
        said: what a report says of an episode that kept the rule, and of one that broke it (the
            trial's headline; empty: the criterion's name and its verdict).
        headline: the names of its fields a trial's headline shows beside its verdict.
        card: the scorecard measure its verdict makes over a row's episodes: (the measure's name,
            True: the share that kept the rule, higher is better; False: the share that broke it,
            lower is better); None: its pass rate is in the summaries only.
    """

    name: ClassVar[str] = "criterion"
    checks: ClassVar[str] = ""
    penalty: ClassVar[float] = 1.0
    terminates: ClassVar[bool] = False
    optional: ClassVar[bool] = False
    fields: ClassVar[tuple[Field, ...]] = ()
    said: ClassVar[tuple[str, str]] = ("", "")
    headline: ClassVar[tuple[str, ...]] = ()
    card: ClassVar[tuple[str, bool] | None] = None

    def applies(self, episode: "Episode") -> bool:
        """Whether the rule holds in this episode at all (where it does not, it neither passes nor fails)."""
        return True

    def passed(self, episode: "Episode") -> bool:
        """Whether the episode kept the rule (asked only where it applies)."""
        raise NotImplementedError

    def measures(self, episode: "Episode") -> dict[str, Any]:
        """The values of its ``fields`` (asked only where it applies)."""
        return {}

    def fails_at(self, row: dict) -> bool:
        """For a criterion that ``terminates``: whether this step's row (the step log's, the world
        managers' columns included) breaks the rule, so that the episode ends here."""
        return False

    @classmethod
    def defaults(cls) -> dict[str, Any]:
        return {cls.name: None} | {f.name: f.default for f in cls.fields}


def _standing_slots(log: pd.DataFrame) -> set:
    """The target slots of the log where a real target stood all along (every slot without the column)."""
    if "sign_stands" not in log:
        return set(log["slot"].unique())
    stands = log.groupby("slot", sort=True)["sign_stands"].all()
    return {slot for slot, standing in stands.items() if standing}


def standing_outcomes(log: pd.DataFrame) -> list[TargetOutcome]:
    """The outcome of every target that stood (the stop rule's targets), in the order they were met."""
    standing = _standing_slots(log)
    return [o for o in score_log(log) if o.slot in standing]


class StopRule(Criterion):
    """Stop at every target that stands: at rest with the front bumper 0-0.60 m before its line."""

    name = "stop_rule"
    checks = "the car came to rest 0-0.60 m before the line of every target that stands"
    penalty = STOP_RULE_PENALTY
    said = ("success", "no success")

    def applies(self, episode: "Episode") -> bool:
        return bool(_standing_slots(episode.log))

    def passed(self, episode: "Episode") -> bool:
        return all(o.success for o in standing_outcomes(episode.log))


class NoNeedlessStop(Criterion):
    """Where no target stands (a sign removed, a phantom picture), drive on: no brake to rest."""

    name = "no_needless_stop"
    checks = "where no real target stands, the car did not brake to rest"
    penalty = NEEDLESS_STOP_PENALTY
    said = ("drove on where nothing stood", "stopped where nothing stood")

    def applies(self, episode: "Episode") -> bool:
        log = episode.log
        return "sign_stands" in log and not bool(log["sign_stands"].all())

    def passed(self, episode: "Episode") -> bool:
        log = episode.log
        at_rest = (log["speed"].abs() < AT_REST_MPS) & log["brake"].astype(bool) & (log["t"] > 0)
        return not bool(at_rest.any())


class NoContact(Criterion):
    """Touch none of a kind of thing (CARLA's ``CollisionTest``): fails at the first step the car touches
    one (the log's ``collision_with``, named as a world manager names its body), and ends the episode
    there. A subclass says what it guards (:meth:`guards`), its name, what it checks and its penalty."""

    terminates = True

    def guards(self, touched: str) -> bool:
        """Whether touching ``touched`` (a name from ``collision_with``) breaks this rule."""
        raise NotImplementedError

    def passed(self, episode: "Episode") -> bool:
        return not any(self.guards(str(who)) for who in episode.log["collision_with"] if who)

    def fails_at(self, row: dict) -> bool:
        return bool(row["collision_with"]) and self.guards(str(row["collision_with"]))


#: The criteria of racf's target approaches (``Scenario.criteria``'s default).
TARGET_CRITERIA: tuple[type[Criterion], ...] = (StopRule, NoNeedlessStop)


def verdict_line(row: dict, criteria) -> str:
    """A result row's headline, from its scenario's ``criteria``: what each one that applied says
    (``Criterion.said``; the stop rule's failure in brackets), then the fields each names in its
    ``headline``; '' where none applied. Every report of one episode says it the same way."""
    words, measures = [], []
    for criterion in criteria:
        verdict = row.get(criterion.name)
        if verdict is None:
            continue
        kept, broken = criterion.said
        if not criterion.optional:
            said = (kept or f"{criterion.name} kept") if verdict else (broken or f"{criterion.name} broken")
            if not verdict and row.get("failure") and criterion.name == "stop_rule":
                said += f" ({row['failure']})"
            words.append(said)
        for name in criterion.headline:
            value = row.get(name)
            if isinstance(value, (int, float)) and value == value:
                unit = next((f.unit for f in criterion.fields if f.name == name), "")
                measures.append(f"{name.removesuffix('_' + unit) if unit else name} {value:.3g}{' ' + unit if unit else ''}")
    return ", ".join(words + measures)
