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
from tests.conftest import TEST_FLEET

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


CONTEXT = StageContext(None, (0.095, 0.032), 0.172, (0.0, 0.0), 0.12, make_defence=Asked,
                       fleet_keys=TEST_FLEET.trust_store())


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


# -- the car ahead's broadcast -----------------------------------------------------------------------------
from racf.experiments.car.broadcast import AGREE_M  # noqa: E402
from racf.experiments.car.following.stage import TRUST_STEPS  # noqa: E402
from racf.sim.radio import RADIO_SLOTS, SIGNED_BYTES, Broadcast, V2VMessage, sign  # noqa: E402
from racf.sim.world.manager import QCAR2_BOX_M  # noqa: E402
from racf.sim.world.road_graph import Path  # noqa: E402

LANE = Path(np.column_stack([np.linspace(0, 10, 101), np.zeros(101)]), np.zeros(101), np.zeros(101))


def _radio_view(k: int, rear_m: float, lead_mps: float, speed: float = 1.0) -> CarView:
    """Step ``k``'s view with a message from the lead whose rear is ``rear_m`` ahead of the camera now."""
    now = 0.02 * k
    x = CONTEXT.camera_xy_m[0] + rear_m + QCAR2_BOX_M[0] / 2
    raw = sign(V2VMessage(k + 1, now, Broadcast(1, x, 0.0, 0.0, lead_mps, 0.0, False)), TEST_FLEET.signing_key(1))
    rows = np.zeros(RADIO_SLOTS * SIGNED_BYTES, np.uint8)
    rows[:SIGNED_BYTES] = np.frombuffer(raw, np.uint8)
    obs = {**OBS, "radio": rows, "radio_times": np.full(RADIO_SLOTS, now), "timestamps": np.full(5, now)}
    return CarView(obs, np.zeros(3), LANE, 0.0, speed, 0.0, 0.0, 0.02, True, False, None)


@pytest.mark.parametrize("defended,told,followed,nearer", [
    (2.5, 1.0, 1.0, True),  # the sensors spoofed away: the broadcast is nearer, and followed
    (1.0 + AGREE_M / 2, 1.0, 1.0 + AGREE_M / 2, False),  # they agree: the defence's own distance
    (1.0, 2.5, 1.0, False),  # the broadcast farther (a liar): the sensors are nearer, and followed
    (math.nan, 1.2, 1.2, True),  # the sensors have none: the broadcast alone
])
def test_the_car_follows_the_more_cautious_of_its_defence_and_the_broadcast_and_says_which(
        defended, told, followed, nearer):
    s = stage(PerceptionSample(None, defended, 0.9, defended, 0.0))
    said = s.step(_radio_view(0, told, 0.5))
    lead = said.detail
    # (the chord from the camera, 3.2 cm left of the car's axis, to the lead's rear: within a millimetre)
    assert lead.followed_m == pytest.approx(followed, abs=1e-3) and said.values["lead_bc_nearer"] is nearer
    assert lead.decision.gap_m == pytest.approx(followed - 0.12, abs=1e-3)
    assert math.isnan(lead.d_fused) if math.isnan(defended) else lead.d_fused == defended
    assert said.values["lead_d_bc"] == pytest.approx(told, abs=1e-3) and said.values["lead_bc_accepted"] == 1


def test_the_leads_speed_is_the_broadcasts_while_it_agrees_with_the_track_else_the_slower():
    def run(told_mps):
        s = stage(PerceptionSample(None, 1.0, 0.9, 1.0, 0.0), FollowingConfig())
        told = []
        for k in range(60):  # the range stays put at 1 m/s: the track confirms a lead at 1 m/s
            told.append(s.step(_radio_view(k, 1.0, told_mps)).detail)
        return s, told[-1]

    s, out = run(1.1)
    assert out.lead_mps == pytest.approx(1.1) and out.speed_known  # agreeing: the broadcast's, the finer
    assert s.estimator.speeds[-1] == pytest.approx(1.0 - 1.1)  # the defence is given the closing speed it makes
    s, out = run(2.0)  # a lead that says it is faster than the car's track sees: the slower, the track's
    assert out.lead_mps == pytest.approx(1.0, abs=0.05) and out.lead_mps < 2.0
    s, out = run(0.2)  # one that says it is slower: the slower, the broadcast's
    assert out.lead_mps == pytest.approx(0.2)


def test_a_defence_that_asks_for_the_broadcast_is_handed_the_checked_witness_each_step():
    class Listens(Asked):
        heard = []

        def hear_broadcast(self, witness):
            self.heard.append(witness)

    s = FollowingStage(CONTEXT, Seen(PerceptionSample(None, 1.0, 0.9, 1.0, 0.0)), estimator=Listens(),
                       config=FollowingConfig(confirm_frames=0))
    s.step(_radio_view(0, 1.0, 0.5))
    s.step(CarView(OBS, np.zeros(3), LANE, 0.0, 1.0, 0.0, 0.0, 0.02, True, False, None))  # no radio: None
    assert s.estimator.heard[0].distance_m == pytest.approx(1.0, abs=1e-3) and s.estimator.heard[1] is None


def test_the_broadcast_earns_trust_by_agreeing_and_loses_it_at_the_first_disagreement():
    s = stage(PerceptionSample(None, 1.0, 0.9, 1.0, 0.0))
    trusted = [s.step(_radio_view(k, 1.0, 0.5)).values["lead_bc_trusted"] for k in range(TRUST_STEPS)]
    assert trusted == [False] * (TRUST_STEPS - 1) + [True]
    s.perception.sample = PerceptionSample(None, math.nan, 0.0, math.nan, math.nan)  # the sensors blind: no verdict
    assert s.step(_radio_view(TRUST_STEPS, 1.5, 0.5)).values["lead_bc_trusted"]
    s.perception.sample = PerceptionSample(None, 1.0, 0.9, 1.0, 0.0)
    assert not s.step(_radio_view(TRUST_STEPS + 1, 1.5, 0.5)).values["lead_bc_trusted"]  # the lead lied: lost
    assert not s.step(_radio_view(TRUST_STEPS + 2, 1.0, 0.5)).values["lead_bc_trusted"]  # and not back at once
