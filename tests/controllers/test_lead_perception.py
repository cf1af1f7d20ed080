"""Perception of the car ahead: the lane placed in the camera, and a detection kept to it."""

import math

import numpy as np
import pytest

from racf.controllers.detector import Detection
from racf.controllers.distance import CameraModel
from racf.controllers.lead_perception import LeadPerception, lane_in_camera
from racf.controllers.vehicle_detector import VEHICLE_BOX_HEIGHT_M

CAMERA = CameraModel(width=320, fx=230.0, cx=160.0, fy=230.0, cy=120.0)


def test_the_lane_is_placed_ahead_of_the_camera_from_the_car_s_pose():
    points = np.array([[2.0, 1.0], [1.0, 3.0]])
    lane = lane_in_camera(points, np.array([1.0, 1.0, math.pi / 2]), (0.1, 0.0))
    # Facing +y from (1, 1): the camera stands at (1, 1.1); (1, 3) is 1.9 m ahead, (2, 1) to the right.
    assert lane[1] == pytest.approx([1.9, 0.0]) and lane[0] == pytest.approx([-0.1, -1.0])


def box_at(z: float, u_centre: float) -> Detection:
    """A car's box at depth ``z`` centred on column ``u_centre`` (its height from the car's)."""
    h = int(round(CAMERA.fy * VEHICLE_BOX_HEIGHT_M / z))
    w = int(round(CAMERA.fx * 0.19 / z))
    x0, y1 = int(u_centre - w / 2), int(round(CAMERA.cy + CAMERA.fy * 0.172 / z))  # its wheels on the floor
    mask = np.zeros((240, 320), bool)
    mask[max(y1 - h, 0):y1, x0:x0 + w] = True
    return Detection(mask, (x0, y1 - h, x0 + w, y1), 0.9, int(mask.sum()), (u_centre, y1 - h / 2))


class Boxes:
    """A detector that reports given boxes."""

    def __init__(self, boxes):
        self.boxes = boxes

    def passing(self, rgb):
        return list(self.boxes)

    @staticmethod
    def largest(detections):
        return max(detections, key=lambda d: d.area_px) if detections else None


STRAIGHT = np.column_stack([np.linspace(0.1, 4.0, 80), np.zeros(80)])


def perceive(boxes, lane):
    perception = LeadPerception(CAMERA, Boxes(boxes))
    image = np.zeros((240, 320, 3), np.uint8)
    return perception.process(image, np.full((240, 320), 1.0, np.float32), None, lane=lane)


def test_a_car_on_the_lane_is_the_car_ahead_and_one_beside_it_is_not():
    ahead, beside = box_at(1.0, 160.0), box_at(1.0, 300.0)
    assert perceive([beside, ahead], STRAIGHT).detection is ahead
    assert perceive([beside], STRAIGHT).detection is None
    assert perceive([ahead], None).detection is None  # no lane known: no car ahead


def test_a_box_whose_size_the_lane_s_distance_cannot_explain_is_not_the_car_ahead():
    # Centred on the lane, but the lane runs out at 1.5 m and the box says 3 m.
    short_lane = STRAIGHT[STRAIGHT[:, 0] <= 1.5]
    assert perceive([box_at(3.0, 160.0)], short_lane).detection is None
    assert perceive([box_at(1.2, 160.0)], short_lane).detection is not None


def test_of_two_cars_on_the_lane_the_nearer_is_followed_and_its_size_gives_its_distance():
    near, far = box_at(0.8, 160.0), box_at(2.0, 160.0)
    sample = perceive([far, near], STRAIGHT)
    assert sample.detection is near and sample.d_size == pytest.approx(0.8, rel=0.05)


def test_the_existence_check_s_evidence_reaches_the_defence_with_the_sample():
    from racf.controllers.lead_existence import NO_EVIDENCE, LeadEvidence, LeadExistenceCheck

    perception = LeadPerception(CAMERA, Boxes([box_at(1.0, 160.0)]), existence=LeadExistenceCheck(CAMERA, 0.172))
    image, wall = np.zeros((240, 320, 3), np.uint8), np.full((240, 320), 1.0, np.float32)
    sample = perception.process(image, wall, None, lane=STRAIGHT)
    assert isinstance(sample.witnesses, LeadEvidence) and sample.witnesses.support > 0.9
    assert sample.witnesses.nearest_m == pytest.approx(1.0)
    perception.detector = Boxes([])
    assert perception.process(image, wall, None, lane=STRAIGHT).witnesses is NO_EVIDENCE
    assert perceive([box_at(1.0, 160.0)], STRAIGHT).witnesses is None  # no check: no evidence


def test_the_existence_check_runs_on_new_frames_only():
    from racf.controllers.lead_existence import LeadExistenceCheck

    class Counting(LeadExistenceCheck):
        updates = 0

        def update(self, *args, **kwargs):
            Counting.updates += 1
            return super().update(*args, **kwargs)

    perception = LeadPerception(CAMERA, Boxes([box_at(1.0, 160.0)]), existence=Counting(CAMERA, 0.172))
    image, wall = np.zeros((240, 320, 3), np.uint8), np.full((240, 320), 1.0, np.float32)
    perception.process(image, wall, None, lane=STRAIGHT)
    held = perception.process(None, None, None, lane=None, new_frame=False)
    assert Counting.updates == 1 and held.witnesses.support > 0.9  # the frame's evidence, held with it
