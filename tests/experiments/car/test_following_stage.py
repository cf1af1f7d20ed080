"""The car's following stage: the defence asked with the closing speed, the gap less the bumper, a lead
unseen too long lost."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from racf.controllers.following import FollowingConfig
from racf.controllers.perception import PerceptionSample
from racf.experiments.car.following.stage import LOST_AFTER_S, FollowingStage
from racf.experiments.car.stage import CarView, StageContext

PATH = SimpleNamespace(arclength=np.linspace(0.0, 5.0, 51), points=np.column_stack([np.linspace(0.0, 5.0, 51),
                                                                                    np.zeros(51)]))
OBS = {"rgb": np.zeros((240, 320, 3), np.uint8), "depth": np.zeros((240, 320, 1), np.float32), "lidar": np.zeros(360)}


class Seen:
    """A perception that reports a given sample and remembers what it was asked."""

    def __init__(self, sample):
        self.sample, self.asked, self.lost = sample, [], 0

    def reset(self):
        pass

    def lose(self):
        self.lost += 1

    def process(self, rgb, depth, scan, **kwargs):
        self.asked.append(kwargs)
        return self.sample


class Asked:
    """A defence that answers the depth and remembers the speed it was given."""

    def __init__(self):
        self.speeds, self.resets = [], 0

    def reset(self):
        self.resets += 1

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0):
        self.speeds.append(speed_mps)
        return sample.d_meas


CONTEXT = StageContext(None, (0.095, 0.032), 0.172, (0.0, 0.0), 0.12, make_defence=Asked)


def stage(sample, config=FollowingConfig(confirm_frames=0)):
    return FollowingStage(CONTEXT, Seen(sample), config=config)


def step(s, speed=1.0, frame_new=True):
    said = s.step(CarView(OBS, np.zeros(3), PATH, 0.0, speed, 0.0, 0.0, 0.02, frame_new, False, None))
    assert said.speed_cap_mps == said.detail.decision.speed_cap_mps and set(said.values) == {c.name for c in s.columns}
    return said.detail


def test_the_defence_and_the_tracker_are_given_the_closing_speed():
    # Depth and LiDAR agree on a range that stays put while the car drives at 1 m/s: the lead drives at 1 m/s.
    s = stage(PerceptionSample(None, 1.0, 0.9, 1.0, 0.0))
    for _ in range(60):
        out = step(s)
    assert out.lead_mps == pytest.approx(1.0, abs=0.05)
    assert s.estimator.speeds[0] == pytest.approx(1.0) and s.estimator.speeds[-1] == pytest.approx(0.0, abs=0.05)
    assert s.perception.asked[-1]["speed"] == pytest.approx(0.0, abs=0.05)


def test_the_gap_is_the_camera_s_distance_less_the_bumper():
    s = stage(PerceptionSample(None, 1.0, 0.9, math.nan, 0.0))
    out = step(s)
    assert out.decision.gap_m == pytest.approx(1.0 - 0.12)
    assert out.decision.speed_cap_mps == pytest.approx((0.88 - 0.25) / 1.0)


def test_a_lead_unseen_too_long_is_lost_and_the_defence_starts_again():
    s = stage(PerceptionSample(None, 1.0, 0.9, 1.0, 0.0))
    step(s)
    s.perception.sample = PerceptionSample(None, math.nan, 0.0, math.nan, math.nan)
    steps = int(LOST_AFTER_S / 0.02)
    for _ in range(steps - 1):
        step(s)
    assert s.estimator.resets == 0
    step(s)
    step(s)
    lost = step(s)
    assert math.isnan(lost.d_fused) and lost.decision.speed_cap_mps == math.inf and s.estimator.resets == 1
    assert step(s).decision.speed_cap_mps == math.inf and s.estimator.resets == 1  # reset once, when lost
    assert s.perception.lost == 1  # and the existence check forgets this lead


def test_a_car_closing_fast_on_a_standing_lead_brakes_in_an_emergency():
    """The policy is given the closing speed (the car's less the lead's): a standing lead 0.7 m ahead of
    the bumper, the car at 1 m/s, is 0.7 s away: under the 0.8 s threshold. With the speeds swapped the
    time-to-collision would read infinite and only the headway cap would act."""
    s = stage(PerceptionSample(None, 1.0, 0.9, 1.0, 0.0))
    out = None
    for k in range(40):  # the range shrinks at the car's speed: the lead stands
        d = 1.5 - 0.02 * k
        s.perception.sample = PerceptionSample(None, d, 0.9, d, 0.0)
        out = step(s, speed=1.0)
    assert out.lead_mps == pytest.approx(0.0, abs=0.1)
    assert out.decision.emergency and out.decision.speed_cap_mps == 0.0
    assert out.decision.ttc_s == pytest.approx(out.decision.gap_m / 1.0, rel=0.1)
