"""The criteria metric: each criterion of the episode's scenario gives its verdict where its rule
applies (None where it does not), its measures, and the driving score is the product of the failed
ones' penalties (an optional one costs nothing). A criterion or a metric that raises costs its own
fields, logged in one line naming it, never the episode."""

from __future__ import annotations

import logging
import math
from types import SimpleNamespace

import pandas as pd
import pytest

from racf.experiments.episode.criteria import Criterion
from racf.experiments.metrics import Field, Metric
from racf.experiments.metrics.criteria import Criteria


def _criterion(name, *, applies=True, passed=True, penalty=0.5, optional=False, raises=False):
    class Made(Criterion):
        fields = (Field(f"{name}_m", math.nan, "m", "a measure"),)

        def applies(self, episode):
            return applies

        def passed(self, episode):
            if raises:
                raise KeyError("no such column")
            return passed

        def measures(self, episode):
            return {f"{name}_m": 1.0}

    Made.name, Made.penalty, Made.optional = name, penalty, optional
    return Made


def _episode(*criteria):
    scenario = SimpleNamespace(criteria=criteria)
    return SimpleNamespace(spec=SimpleNamespace(scenario=scenario, target="mine", trial_id="t1"),
                           log=pd.DataFrame({"t": [0.0]}))


def test_the_driving_score_is_the_product_of_the_failed_criterias_penalties():
    row = Criteria().score(_episode(_criterion("a", passed=False, penalty=0.8), _criterion("b", passed=True),
                                    _criterion("c", passed=False, penalty=0.5),
                                    _criterion("d", passed=False, penalty=0.1, optional=True),
                                    _criterion("e", applies=False, passed=False, penalty=0.1)))
    assert row["driving_score"] == pytest.approx(0.8 * 0.5)
    assert (row["a"], row["b"], row["c"], row["d"], row["e"]) == (False, True, False, False, None)
    assert row["a_m"] == 1.0 and math.isnan(row["e_m"])  # measures only where the rule applies


def test_a_criterion_that_raises_costs_its_own_fields_and_is_named(caplog):
    with caplog.at_level(logging.WARNING):
        row = Criteria().score(_episode(_criterion("ok", passed=False, penalty=0.8), _criterion("bad", raises=True)))
    assert row["bad"] is None and math.isnan(row["bad_m"]) and row["ok"] is False and row["driving_score"] == 0.8
    assert "criterion 'bad' of scenario 'mine' raised KeyError" in caplog.text and "t1" in caplog.text


class _Boom(Metric):
    name = "boom"
    fields = (Field("boom_value", math.nan, "", "never filled"),)

    def score(self, episode):
        raise LookupError("a plug-in's bug")


def test_a_metric_that_raises_costs_its_own_fields_not_the_episode(caplog):
    from racf.experiments.episode import TrialSpec, run_trial
    from racf.plugins import METRICS

    METRICS.register(_Boom)
    try:
        with caplog.at_level(logging.WARNING):
            result, _ = run_trial(TrialSpec("clean", 2, 1.0, 0, metrics=("boom",)), clean_pass=False)
    finally:
        METRICS._all().pop("boom")
    row = result.to_dict()
    assert row["boom_value"] is None and row["success"] is True and row["driving_score"] == 1.0
    assert "metric 'boom' raised LookupError: a plug-in's bug" in caplog.text


class _OneSecond(Criterion):
    name, checks, terminates = "under_a_second", "the episode lasts under a second", True

    def passed(self, episode):
        return float(episode.log["t"].iloc[-1]) < 1.0

    def fails_at(self, row):
        return row["t"] >= 1.0


def test_a_criterion_that_terminates_ends_the_episode_at_the_step_that_breaks_it():
    from racf.experiments.episode import TrialSpec, run_trial
    from racf.experiments.scenarios import Scenario
    from racf.plugins import SCENARIOS

    class Hurried(Scenario):
        name = "hurried_test"
        criteria = (*Scenario.criteria, _OneSecond)

    SCENARIOS.register(Hurried)
    try:
        result, log = run_trial(TrialSpec("clean", 2, 1.0, 0, target="hurried_test"), clean_pass=False)
    finally:
        SCENARIOS._all().pop("hurried_test")
    assert log["t"].iloc[-1] == pytest.approx(1.0) and result.under_a_second is False
    assert result.driving_score == pytest.approx(0.8 * 1.0)  # the stop rule broken too; its own penalty 1.0


def test_a_contact_rule_fails_at_the_step_the_car_touches_what_it_guards():
    from racf.experiments.episode.criteria import NoContact

    class NoPosts(NoContact):
        name, checks = "no_posts", "the car touched no post"

        def guards(self, touched):
            return touched.startswith("post")

    rule = NoPosts()
    assert rule.terminates
    assert [rule.fails_at({"collision_with": w}) for w in ("", "post3", "wall")] == [False, True, False]
    log = pd.DataFrame({"collision_with": ["", "", "wall"]})
    assert rule.passed(SimpleNamespace(log=log)) and not rule.passed(SimpleNamespace(log=log.assign(collision_with="post1")))
