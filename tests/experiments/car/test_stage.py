"""The car stage contract: a stage's cap joins the braker's and the lowest wins, its declared columns
reach the row before it ever steps, and a stage is a registered part like the others."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.experiments.car.stage import CarStage, StageColumn, StageLimit
from racf.experiments.episode import TrialSpec, run_trial
from racf.plugins import CAR_STAGES, PluginError


class Capped(CarStage):
    """Caps the car at a fixed speed and logs what it saw."""

    name = "capped_test"
    columns = (StageColumn("capped_cap", "m/s", "the cap"), StageColumn("capped_new", "bool", "a new frame"))
    cap = 0.3

    def reset(self):
        self.steps = 0

    def step(self, view):
        self.steps += 1
        return StageLimit(self.cap, {"capped_cap": self.cap, "capped_new": view.frame_new})


def test_a_stage_s_idle_values_are_nan_or_false_and_its_cap_none():
    idle = Capped(None).idle()
    assert math.isinf(idle.speed_cap_mps) and math.isnan(idle.values["capped_cap"]) and idle.values["capped_new"] is False


def test_a_stage_is_a_part_and_an_unknown_one_is_named():
    CAR_STAGES.register(Capped)
    assert CAR_STAGES["capped_test"] is Capped and "following" in CAR_STAGES
    with pytest.raises(PluginError, match="unknown car stage 'nowhere'"):
        CAR_STAGES.plugin("nowhere")


@pytest.fixture(scope="module")
def staged_episode():
    """A sign approach whose mission engages the test's stage (a scenario of the test's, in the session)."""
    import dataclasses

    from racf.experiments.scenarios import Scenario
    from racf.plugins import SCENARIOS

    class Staged(Scenario):
        name = "staged_test"

        def plan(self, spec, values, draft):
            return self.replace(draft, mission=dataclasses.replace(draft.mission, stages=("capped_test",)))

    CAR_STAGES.register(Capped)
    SCENARIOS.register(Staged)
    return run_trial(TrialSpec("clean", 1, 1.0, 0, target="staged_test"), clean_pass=False)


def test_the_lowest_cap_wins_and_the_stage_s_columns_are_the_car_s(staged_episode):
    result, log = staged_episode
    assert (log["capped_cap"] == 0.3).all() and log["capped_new"].any() and not log["capped_new"].all()
    # The car drove at the stage's cap, though its cruise (1 m/s) and the braker allowed more.
    settled = (log["t"] > 2.0) & (log["phase"] != "done") & (log["speed_cap"] > 0.3)
    assert settled.sum() > 50 and log.loc[settled, "state_speed_mps"].between(0.25, 0.33).all()
    assert list(log.columns)[-2:] == ["capped_cap", "capped_new"]  # after racf's own columns (and before a world's)
    from racf.experiments.episode.record import CAR, stage_columns

    assert {c.side for c in stage_columns([Capped])} == {CAR}


@given(st.lists(st.floats(0.0, 5.0) | st.just(math.inf), min_size=1, max_size=4), st.floats(0.0, 5.0))
def test_the_car_takes_the_lowest_of_every_cap(caps, braker):
    from racf.experiments.car.software import lowest_cap

    assert lowest_cap(braker, [StageLimit(c) for c in caps]) == min([braker, *caps])


def test_a_stage_is_handed_the_scan_only_on_the_step_it_arrives_and_what_it_is_handed_is_frozen():
    import dataclasses

    import numpy as np

    from racf.experiments.car.stage import CarView, StageContext

    scan = np.arange(360.0)
    view = CarView({"lidar": scan}, np.zeros(3), None, 0.0, 1.0, 0.0, 0.0, 0.02, True, True)
    assert view.scan is scan and dataclasses.replace(view, scan_new=False).scan is None
    context = StageContext(None, (0.1, 0.0), 0.17, (0.0, 0.0), 0.12, make_defence=object)
    for frozen in (view, context, StageLimit(1.0), StageColumn("a", "m", "b")):
        with pytest.raises(dataclasses.FrozenInstanceError):
            frozen.name = "changed"


def test_a_track_says_only_what_its_stage_says_and_is_frozen():
    """A published track's unsaid fields: a static target at its face, its speed 0 and known, no broadcast
    trusted, the publisher's first target."""
    import dataclasses

    from racf.experiments.car.stage import TargetTrack

    track = TargetTrack("sign", 1.5, math.inf)
    assert (track.moving, track.speed_mps, track.speed_known, track.stop_at_m, track.broadcast_trusted,
            track.index) == (False, 0.0, True, 0.0, False, 0)
    assert all(math.isnan(v) for v in (track.depth_m, track.lidar_m, track.size_m, track.map_m, track.line_m))
    with pytest.raises(dataclasses.FrozenInstanceError):
        track.distance_m = 9.0
