"""Defences that answer whether a sign stands (racf.experiments.car.existence_defences), and the car
acting on that answer."""

import math

import pytest

from racf.controllers import PerceptionSample
from racf.controllers.existence import ExistenceWitnesses
from racf.experiments.car.existence_defences import DetectorsOr, ExistenceVote, MapOnly
from racf.experiments.episode.plan import car_calibration
from racf.experiments.episode.stack import existence_stage


def _sample(witnesses, d_meas=math.nan, detected=False):
    import numpy as np

    from racf.controllers.detector import Detection

    detection = Detection(np.zeros((4, 4), bool), (0, 0, 2, 2), 0.9, 4, (1.0, 1.0)) if detected else None
    return PerceptionSample(detection, d_meas, 0.9 if detected else 0.0, math.nan, math.nan, witnesses=witnesses)


def _w(seen=(False, False), detectors=(False, False), depth=False, blind=False, mapped=False, depth_m=math.nan,
       map_depth_m=math.nan, seen_depth=(math.nan, math.nan), moving=False):
    return ExistenceWitnesses(seen, seen_depth, detectors, depth, False, blind, mapped, depth_m, map_depth_m,
                              "map" if mapped else "detector", moving=moving)


def _ready(defence):
    defence.reset()  # the car resets a defence before each target
    return defence


def test_the_vote_stops_for_a_mapped_plate_no_detector_sees_at_the_plates_depth():
    vote = _ready(ExistenceVote(inner="raw"))
    assert vote.stands() is None  # before any step it defers
    d = vote.estimate(_sample(_w(depth=True, mapped=True, depth_m=1.2, map_depth_m=1.3)), 1.0, 0.02)
    assert vote.stands() is True and d == 1.2
    assert vote.diagnostics()["stands"] == 1.0 and vote.diagnostics()["wit_map"] == 1.0


def test_the_vote_keeps_the_inner_defences_distance_while_the_detector_sees_the_sign():
    vote = _ready(ExistenceVote(inner="raw"))
    assert vote.estimate(_sample(_w(detectors=(True, True), depth=True, depth_m=1.2), 1.25, True), 1.0, 0.02) == 1.25


def test_a_blinded_mapped_place_brakes_at_the_maps_distance():
    vote = _ready(ExistenceVote(inner="raw"))
    assert vote.estimate(_sample(_w(blind=True, mapped=True, map_depth_m=1.4)), 1.0, 0.02) == 1.4 and vote.stands()


def test_a_depth_caught_moving_at_a_mapped_place_brakes_at_the_maps_distance_not_the_inner_defences():
    vote = _ready(ExistenceVote(inner="raw"))
    caught = _w(detectors=(True, False), mapped=True, moving=True, depth_m=5.0, map_depth_m=1.4)
    assert vote.estimate(_sample(caught, 5.1, True), 1.0, 0.02) == 1.4 and vote.stands()
    unmapped = _w(detectors=(True, False), depth=True, moving=True, depth_m=5.0)  # no map entry to hold to
    assert vote.estimate(_sample(unmapped, 5.1, True), 1.0, 0.02) == 5.1


def test_the_vote_carries_its_last_distance_on_by_odometry_once_no_witness_is_left():
    vote = _ready(ExistenceVote(inner="raw"))
    vote.estimate(_sample(_w(depth=True, mapped=True, depth_m=1.0)), 1.0, 0.02)
    assert vote.estimate(_sample(_w()), 1.0, 0.1) == pytest.approx(0.9) and vote.stands() is False


def _lead(evidence, d_meas=1.0, lidar=math.nan, size=1.0):
    import numpy as np

    from racf.controllers.detector import Detection

    detection = Detection(np.zeros((4, 4), bool), (0, 0, 2, 2), 0.9, 4, (1.0, 1.0))
    return PerceptionSample(detection, d_meas, 0.9, lidar, 0.0, d_size=size, size_std=0.05, witnesses=evidence)


class _Inner:
    """An inner defence that reads the depth and counts its resets."""

    def __init__(self):
        self.resets, self.seen = 0, []

    def reset(self):
        self.resets += 1

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0):
        self.seen.append(sample)
        return sample.d_meas


def test_the_vote_follows_what_stands_on_the_lane_while_the_car_ahead_s_box_is_a_picture():
    from racf.controllers.lead_existence import LeadEvidence

    off = _ready(ExistenceVote(inner="raw"))  # by default the vote leaves the car ahead to its inner defence
    assert off.estimate(_lead(LeadEvidence(0.0, 1.6, True, True), d_meas=0.9, size=0.5), 0.5, 0.02) == 0.9
    vote = _ready(ExistenceVote(inner="raw", lead_check=True))
    vote.inner = inner = _Inner()
    held = LeadEvidence(0.9, 1.6, False, False)
    assert vote.estimate(_lead(held, d_meas=1.6), 0.5, 0.02) == 1.6 and vote.stands() is None
    picture = LeadEvidence(0.0, 1.6, True, True)
    assert vote.estimate(_lead(picture, d_meas=0.9, size=0.5), 0.5, 0.02) == 1.6  # not the box's depth
    assert vote.estimate(_lead(picture, d_meas=0.9, lidar=1.5), 0.5, 0.02) == 1.5  # the nearer of the two
    assert len(inner.seen) == 1  # the inner defence never reads the picture
    # Nothing stands in the box and no LiDAR: the last distance carried by the closing speed.
    assert vote.estimate(_lead(LeadEvidence(0.0, math.nan, True, True)), 0.5, 0.1) == pytest.approx(1.45)
    # The picture gone, the inner defence starts afresh on the car's own box.
    assert vote.estimate(_lead(LeadEvidence(0.9, 1.4, False, True), d_meas=1.4), 0.5, 0.02) == 1.4
    assert inner.resets == 1 and len(inner.seen) == 2


def test_the_baselines_answer_by_their_own_rule():
    either = _ready(DetectorsOr(inner="raw"))
    assert either.estimate(_sample(_w(seen=(False, True), seen_depth=(math.nan, 0.9))), 1.0, 0.02) == 0.9
    assert either.stands() is True
    assert not (either.estimate(_sample(_w(depth=True, mapped=True)), 1.0, 0.02), either.stands())[1]
    only_map = _ready(MapOnly())
    assert only_map.estimate(_sample(_w(map_depth_m=2.0)), 1.0, 0.02) == 2.0 and only_map.stands()
    assert math.isnan(only_map.estimate(_sample(_w(detectors=(True, True), depth=True)), 1.0, 0.02))
    assert not only_map.stands()


def test_the_car_builds_the_stage_only_for_a_defence_that_answers_and_with_the_other_detector():
    calib = car_calibration(320, 240)
    assert existence_stage(object(), calib, "classical") is None
    assert existence_stage(MapOnly(), calib, "classical").second is None
    stage = existence_stage(ExistenceVote(inner="raw", second_detector="classical"), calib, "classical")
    assert type(stage.second.detector).__name__ == "LearnedSignDetector"


@pytest.mark.parametrize("name", ["vote", "detectors_or", "map_only"])
def test_each_is_registered_and_kept_out_of_the_offline_benchmark(name):
    from racf.experiments.offline.methods import offline_estimators
    from racf.plugins import ESTIMATORS

    assert name in ESTIMATORS and name not in offline_estimators()
