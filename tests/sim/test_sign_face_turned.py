"""The referee sees a sign's face only from in front of it, where its body turned it: a sign turned
half round on its pole shows the car its back, though its octagon's outline stands where it stood."""

import math

import numpy as np

from racf.sim.env.ground_truth import Motion, sign_view
from racf.sim.sensors.camera import CameraIntrinsics
from racf.sim.world.stop_signs import stop_signs

K = CameraIntrinsics.d435_colour(320, 240)


def _facing_camera(sign, distance_m: float):
    """A camera ``distance_m`` in front of the map's face, looking at its centre (MuJoCo's axes: x right,
    y up, z backward)."""
    normal = np.array([math.cos(sign.face_yaw), math.sin(sign.face_yaw), 0.0])
    forward, up = -normal, np.array([0.0, 0.0, 1.0])
    right = np.cross(forward, up)
    return sign.centre + distance_m * normal, np.column_stack([right, up, -forward])


def _turned_about_pole(sign, degrees: float) -> Motion:
    a = math.radians(degrees)
    rotation = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])
    pole = np.array([*sign.position, 0.0])
    return Motion(rotation, pole, pole)


def test_a_sign_turned_half_round_shows_its_back_and_no_face():
    sign = stop_signs()[1]
    cam_pos, cam_mat = _facing_camera(sign, 1.0)
    depth = np.full((K.height, K.width), 1.0)  # the face's plane, square to the camera, 1 m away
    assert sign_view(sign, cam_pos, cam_mat, K, depth).mask.sum() > 100
    turned = sign_view(sign, cam_pos, cam_mat, K, depth, motion=_turned_about_pole(sign, 180.0))
    assert not turned.mask.any() and not turned.in_view
    # A small turn leaves the face to the camera.
    assert sign_view(sign, cam_pos, cam_mat, K, depth, motion=_turned_about_pole(sign, 10.0)).mask.any()
