"""The scenario's criteria, judged on every episode (the ``criteria`` metric).

Each criterion of the episode's scenario (``Scenario.criteria``; ``racf.experiments.episode.criteria``)
gives its verdict column (True passed, False failed, None where the rule does not apply) and its
own fields; ``driving_score`` is the product of the failed criteria's penalties (1.0 where none
failed). Over many episodes each verdict is a pass rate with its Wilson interval over the
episodes where its rule applies, and each of its fields is summarised as it declares.
"""

from __future__ import annotations

import logging
import math

import pandas as pd

from racf.experiments.episode.criteria import Criterion
from racf.experiments.metrics.base import Episode, Field, Metric, summarize_fields
from racf.plugins import SCENARIOS

__all__ = ["Criteria", "criteria_of_rows", "scenarios_of", "card_measures"]

_log = logging.getLogger(__name__)


class Criteria(Metric):
    """Every criterion of the episode's scenario: its verdict, its measures and the driving score."""

    name = "criteria"
    meaning = "the scenario's criteria (pass, fail or not applicable, each with its measures) and the driving score"
    always, order = True, 65
    higher_is_better = {"driving_score": True}
    fields = (Field("driving_score", math.nan, "1", "the product of the failed criteria's penalties (CARLA's "
                                                    "infraction coefficients; 1.0: none failed)"),)

    def score(self, episode: Episode) -> dict:
        row: dict = {}
        score = 1.0
        for criterion in (cls() for cls in episode.spec.scenario.criteria):
            row |= judged(criterion, episode, episode.spec.target)
            if row[criterion.name] is False and not criterion.optional:
                score *= criterion.penalty
        return row | {"driving_score": score}

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict:
        """Each criterion's verdict as a rate (the share passed, over the rows where its rule applies),
        and its fields as each declares them."""
        fields = [f for c in criteria_of_rows(results)
                  for f in (Field(c.name, None, "", c.checks, "rate"), *c.fields)]
        return summarize_fields(fields, results)


def judged(criterion: Criterion, episode: Episode, owner: str) -> dict:
    """One criterion's verdict and measures on one episode. A criterion that raises costs its own
    columns (its defaults: None and NaN), logged in one line naming it, never the episode."""
    try:
        if not criterion.applies(episode):
            return criterion.defaults()
        return criterion.defaults() | criterion.measures(episode) | {criterion.name: bool(criterion.passed(episode))}
    except Exception as err:  # a plug-in's fault is its own: the episode's other fields stand
        _log.warning("criterion %r of scenario %r raised %s: %s; its fields are null for episode %s", criterion.name,
                     owner, type(err).__name__, err, episode.spec.trial_id)
        return criterion.defaults()


def scenarios_of(results: pd.DataFrame) -> list:
    """The scenarios the rows ran (each once, by name), as the registry holds them."""
    targets = sorted(results["target"].dropna().unique()) if "target" in results else []
    return [SCENARIOS[t] for t in targets if t in SCENARIOS]


def criteria_of_rows(results: pd.DataFrame) -> list[Criterion]:
    """The criteria of the scenarios the rows ran (each once)."""
    seen: dict[str, Criterion] = {}
    for scenario in scenarios_of(results):
        for cls in scenario.criteria:
            seen.setdefault(cls.name, cls())
    return list(seen.values())


def card_measures(results: pd.DataFrame) -> list[dict]:
    """The scorecard measures the rows' criteria declare (``Criterion.card``): each one's share of the
    episodes where its rule applies that kept it (or broke it), with its Wilson interval and N."""
    from racf.stats import wilson_interval

    out = []
    for criterion in criteria_of_rows(results):
        if criterion.card is None or criterion.name not in results:
            continue
        measure, kept = criterion.card
        verdicts = results[criterion.name].dropna().astype(bool)
        n = int(len(verdicts))
        if not n:
            continue
        k = int(verdicts.sum()) if kept else int((~verdicts).sum())
        out.append({"measure": measure, "value": k / n, "ci": list(wilson_interval(k, n)), "n": n,
                    "higher_is_better": kept})
    return out
