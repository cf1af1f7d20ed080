"""The supervisor's choice: the defence's cap while its distance is vouched; the safe controller's on
the worst case otherwise; a stop once the car is faster than that worst case allows; easing off,
never a hard brake, for what appears from nowhere."""

import math

import numpy as np
import pytest

from racf.controllers.following import FollowDecision, FollowingConfig, LeadSpeed
from racf.controllers.perception import PerceptionSample
from racf.experiments.car.following.stage import LeadStep
from racf.experiments.car.stage import CarView, StageContext, StageLimit
from racf.experiments.car.supervisor.envelope import safe_speed
from racf.experiments.car.supervisor.stage import EASE_MPS2, SupervisorStage

NAN = math.nan
DT = 0.02
BUMPER = 0.1


class Advanced:
    """A following stage that says what it is told to: its witnesses, its distance and its cap."""

    camera_xy_m = (0.2, 0.0)

    def __init__(self) -> None:
        self.config = FollowingConfig()
        self.speed = LeadSpeed(self.config)
        self.next = (NAN, NAN, NAN, math.inf)

    def idle(self):
        return StageLimit(math.inf, {}, None)

    def reset(self):
        pass

    def step(self, view):
        depth, lidar, fused, cap = self.next
        sample = PerceptionSample(None, depth, 0.0, lidar, NAN)
        step = LeadStep(sample, fused, 0.0, FollowDecision(cap, fused - BUMPER, NAN, cap == 0.0))
        return StageLimit(cap, {"lead_cap": cap}, step)


def _stage() -> tuple[SupervisorStage, Advanced]:
    context = StageContext(None, (0.2, 0.0), 0.17, (0.1, 0.0), BUMPER, lambda: None, target_decel_mps2=6.0)
    advanced = Advanced()
    stage = SupervisorStage(context, advanced=advanced)
    stage.reset()
    return stage, advanced


def _view(speed: float) -> CarView:
    return CarView({}, np.zeros(3), None, 0.0, speed, 0.0, 0.0, DT, True, False)


def _say(stage, advanced, speed, depth, lidar, fused, cap):
    advanced.next = (depth, lidar, fused, cap)
    return stage.step(_view(speed))


def test_a_vouched_defence_drives_with_its_own_cap():
    stage, advanced = _stage()
    said = _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    assert said.values["sup_defence"] and said.speed_cap_mps == 0.7 and not said.values["sup_stop"]


def test_a_defence_off_the_vouched_reading_is_set_aside_for_the_safe_controller():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    # A phantom: the defence follows a picture at 0.5 m and stops the car; the range witnesses see the lead.
    said = _say(stage, advanced, 0.5, 1.5, 1.44, 0.5, 0.0)
    assert not said.values["sup_defence"] and said.values["sup_vouched"]
    gap = 1.44 - BUMPER  # a fresh reading: the policy on the reading itself
    assert said.speed_cap_mps == pytest.approx(min((gap - 0.25) / 1.0, safe_speed(gap - 0.1, 0.0, stage.envelope,
                                                                                    stage.envelope.comfort_brake_mps2)))
    assert said.speed_cap_mps > 0.5


def test_a_car_faster_than_the_worst_case_gap_allows_is_told_to_stop_whatever_the_defence_says():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 0.5, 0.5, 0.5, 3.0)
    said = _say(stage, advanced, 2.0, 0.5, 0.5, 0.5, 3.0)
    assert said.values["sup_stop"] and said.speed_cap_mps == 0.0


def test_a_hidden_lead_is_carried_where_it_was_and_the_car_brought_to_rest_behind_it():
    stage, advanced = _stage()
    _say(stage, advanced, 0.8, 1.2, 1.2, 1.2, 0.8)
    speed, caps = 0.8, []
    for _ in range(300):  # 6 s with no witness at all; the defence has let go (no cap)
        said = _say(stage, advanced, speed, NAN, NAN, NAN, math.inf)
        caps.append(said.speed_cap_mps)
        speed = max(min(speed, said.speed_cap_mps), 0.0)
    assert said.values["sup_carried"] and not said.values["sup_vouched"]
    assert caps[-1] < 0.05 and said.values["sup_near"] - BUMPER > 0.0


def test_an_implausible_reading_eases_the_car_off_no_harder_than_ease():
    stage, advanced = _stage()
    _say(stage, advanced, 1.0, 2.0, 2.0, 2.0, 1.0)
    caps = [_say(stage, advanced, 1.0, 0.6, NAN, 0.6, 0.0).speed_cap_mps for _ in range(5)]
    assert caps[0] == pytest.approx(1.0 - EASE_MPS2 * DT) and np.allclose(np.diff(caps), -EASE_MPS2 * DT)


def test_nothing_seen_nothing_limited():
    stage, advanced = _stage()
    said = _say(stage, advanced, 1.0, NAN, NAN, NAN, math.inf)
    assert said.speed_cap_mps == math.inf and not said.values["sup_carried"]
    assert set(said.values) >= {c.name for c in SupervisorStage.columns if c.name.startswith("sup_")}
