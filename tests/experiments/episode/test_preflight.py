"""The preflight plans each episode before any simulator: what a plan declares is checked against the
step log, a value the plan refuses is one line, and a plug-in's bug is left to the episode to name."""

from __future__ import annotations

import dataclasses

import pytest

from racf.errors import UserError
from racf.experiments.car.stage import CarStage, StageColumn
from racf.experiments.episode import TrialSpec
from racf.experiments.episode.preflight import check_plan, check_specs
from racf.experiments.scenarios import Scenario
from racf.plugins import CAR_STAGES, SCENARIOS


class Twice(CarStage):
    name = "twice_test"
    columns = (StageColumn("twice_a", "", "a"), StageColumn("twice_a", "", "again"))


def _scenario(name, stages=(), run_up=None, plan_error=None):
    class Made(Scenario):
        def plan(self, spec, values, draft):
            if plan_error is not None:
                raise plan_error
            return self.replace(draft, mission=dataclasses.replace(draft.mission, stages=stages))

        def run_up(self, spec):
            return run_up

    Made.name = name
    SCENARIOS.register(Made)
    return TrialSpec("clean", 2, 1.0, 0, target=name)


def test_a_plan_the_sign_cannot_have_is_one_line_naming_the_episode():
    with pytest.raises(UserError, match=r"episode clean_far_test2_v1.00_seed0 cannot be planned: .*run_up_m"):
        check_specs([_scenario("far_test", run_up=9.0)])


def test_a_stage_that_declares_one_column_twice_or_is_unknown_is_refused():
    CAR_STAGES.register(Twice)
    with pytest.raises(UserError, match="car stage 'twice_test' declares the column 'twice_a'"):
        check_plan(_scenario("twice_scn", stages=("twice_test",)))
    with pytest.raises(UserError, match="unknown car stage 'gone_test'"):
        check_plan(_scenario("gone_scn", stages=("gone_test",)))
    check_plan(_scenario("fine_scn", stages=("following",)))  # racf's own: nothing to say


def test_a_plug_ins_bug_in_its_plan_is_left_to_the_episode():
    check_plan(_scenario("buggy_scn", plan_error=KeyError("lane")))  # not a value the user gave: no UserError here
