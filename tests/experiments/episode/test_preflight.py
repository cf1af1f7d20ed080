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


def test_a_world_column_named_like_racf_s_is_refused_and_a_sound_batch_passes():
    from racf.sim.world.manager import TruthColumn, WorldManager

    class Clash(WorldManager):
        def columns(self):
            return (TruthColumn("speed", "m/s", "mine"),)

    class Clashing(Scenario):
        name = "clash_scn"

        def world(self, spec, values):
            return (Clash(),)

    SCENARIOS.register(Clashing)
    with pytest.raises(UserError, match="declares the column 'speed', which racf's step log already holds"):
        check_plan(TrialSpec("clean", 2, 1.0, 0, target="clash_scn"))
    check_specs([TrialSpec("clean+depth_bias+raw", 1, 1.0, seed) for seed in range(3)])


class _Boom:
    """An estimator whose constructor fails (a plug-in's)."""

    name = "boom_test"
    why: Exception = RuntimeError("no GPU here")

    def __init__(self):
        raise self.why

    def reset(self): ...

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0): ...

    def diagnostics(self): ...

    def would_pass(self, **kwargs): ...


def test_a_defence_or_an_attack_that_cannot_be_built_is_one_line_naming_it():
    from racf.plugins import ESTIMATORS

    ESTIMATORS.register(_Boom)
    with pytest.raises(UserError, match=r"estimator 'boom_test' with options \{\} cannot be built: RuntimeError: no GPU"):
        check_specs([TrialSpec("clean+boom_test", 1, 1.0, 0)])
    _Boom.why = ValueError("tol_m must be a number")
    with pytest.raises(UserError, match=r"tol_m must be a number$") as caught:  # a ValueError: its words, no type
        check_specs([TrialSpec("clean+boom_test", 1, 1.0, 0)])
    assert "ValueError" not in str(caught.value)
    from racf.plugins import ATTACKS
    from racf.sim.attacks.base import AttackWrapper
    from racf.sim.attacks.schedule import AttackSchedule

    class LateTest(AttackWrapper):
        """Opens its window 200 s in: later than the schedule takes."""

        name = "late_test"

        def __init__(self, env, **schedule):
            super().__init__(env, AttackSchedule(**{**schedule, "trigger": "at_time", "start_s": 200.0}))

    ATTACKS.register(LateTest)
    with pytest.raises(UserError, match=r"attack\(s\) late_test and schedule \(duration_s=.*cannot be built: start_s"):
        check_specs([TrialSpec("clean+late_test", 1, 1.0, 0)])


def test_a_served_defence_is_asked_once_before_any_episode():
    import socket

    with socket.socket() as held:  # bound, not listening: nothing answers there
        held.bind(("127.0.0.1", 0))
        spec = TrialSpec("clean", 1, 1.0, 0, estimator_endpoint=f"tcp://127.0.0.1:{held.getsockname()[1]}",
                         estimator_timeout_ms=100.0)
        with pytest.raises(UserError, match="nothing listens there"):
            check_specs([spec])
