"""Ground truth about the target stop sign as the camera sees it (for ``info`` only).

The sign's pixel mask comes from projecting the octagon through the camera's intrinsics
and keeping the pixels where the noise-free rendered depth agrees with the sign's plane,
so parts hidden behind other objects are excluded. No extra render pass is needed.

The truth follows the world, not the map: a world manager may move, turn or lean a target's
body, and the env hands the body's displacement from its map pose (:class:`Motion`, read from
MuJoCo's body poses after every manager acted) to the views here. The map's record gives the
target's shape in the body; the motion puts it where the body stands now. A body at its map
pose has no motion (None), and its truth is the record's to the bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from racf.sim.sensors.camera import CameraIntrinsics
from racf.sim.world.stop_signs import SIGN_FACE_ACROSS_FLATS_M, StopSign

__all__ = ["SignView", "Motion", "sign_view", "face_area_px", "obstacle_view", "with_centre_from",
           "target_centre"]

#: Converts MuJoCo's camera frame (x right, y up, looking along -z) to the optical frame.
_MJ_TO_OPTICAL = np.diag([1.0, -1.0, -1.0])
_DEPTH_TOLERANCE_M = 0.03
#: A target centre nearer the camera plane than this (or behind it) has no depth or bearing, m.
_BEHIND_M = 0.05


@dataclass(frozen=True)
class SignView:
    """How the camera sees one stop sign.

    Attributes:
        d_true: depth of the octagon's centre along the optical axis, metres (what a depth
            camera measures for it); NaN when the centre is behind the camera.
        d_euclid: straight-line distance from the optical centre to the octagon's centre.
        bearing: angle of the centre from the optical axis, radians (left positive).
        mask: (H, W) bool, visible pixels of the sign's face.
        in_view: whether any pixel of the face is visible.
    """

    d_true: float
    d_euclid: float
    bearing: float
    mask: np.ndarray
    in_view: bool


@dataclass(frozen=True)
class Motion:
    """A body's rigid displacement from its map pose: a point ``p`` of the map's record of the body
    stands at ``rotation @ (p - origin) + position`` in the world now.

    Attributes:
        rotation: (3, 3) the body's rotation now times its map rotation's transpose.
        origin: (3,) the body's origin where the map puts it.
        position: (3,) the body's origin now.
    """

    rotation: np.ndarray
    origin: np.ndarray
    position: np.ndarray

    @classmethod
    def between(cls, home_pos: np.ndarray, home_mat: np.ndarray, pos: np.ndarray, mat: np.ndarray) -> "Motion | None":
        """The motion from a body's map pose (``home_*``) to its pose now (positions (3,), rotations
        as MuJoCo's row-major ``xmat`` (9,) or (3, 3)); None when the body has not moved (exactly)."""
        home_mat, mat = np.asarray(home_mat, np.float64).reshape(3, 3), np.asarray(mat, np.float64).reshape(3, 3)
        if np.array_equal(home_pos, pos) and np.array_equal(home_mat, mat):
            return None
        return cls(mat @ home_mat.T, np.array(home_pos, np.float64), np.array(pos, np.float64))

    def points(self, points: np.ndarray) -> np.ndarray:
        """Points ((3,) or (N, 3)) of the map's record where they stand now."""
        return (np.asarray(points, np.float64) - self.origin) @ self.rotation.T + self.position

    def vector(self, vector: np.ndarray) -> np.ndarray:
        """A direction of the map's record (a face's normal) as it points now."""
        return self.rotation @ np.asarray(vector, np.float64)


def _moved(motion: Motion | None, points: np.ndarray) -> np.ndarray:
    return points if motion is None else motion.points(points)


def target_centre(target, motion: Motion | None = None) -> np.ndarray:
    """(3,) where a target's centre (a sign's octagon, a crate's near face) stands: its record's
    ``centre`` moved by ``motion``."""
    return _moved(motion, target.centre)


def _face_normal(sign: StopSign, motion: Motion | None) -> np.ndarray:
    normal = np.array([math.cos(sign.face_yaw), math.sin(sign.face_yaw), 0.0])
    return normal if motion is None else motion.vector(normal)


def _octagon_world(sign: StopSign) -> np.ndarray:
    r = SIGN_FACE_ACROSS_FLATS_M / (2 * math.cos(math.pi / 8))
    a = math.pi / 8 + np.arange(8) * math.pi / 4
    lateral, up = r * np.cos(a), r * np.sin(a)
    yaw = sign.face_yaw
    left = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
    return sign.centre + lateral[:, None] * left + up[:, None] * np.array([0.0, 0.0, 1.0])


def sign_view(sign: StopSign, cam_pos: np.ndarray, cam_mat: np.ndarray,
              intrinsics: CameraIntrinsics, clean_depth: np.ndarray, motion: Motion | None = None) -> SignView:
    """Ground truth of ``sign`` from a camera pose.

    Args:
        sign: the stop sign (the map's record: its shape in its body).
        cam_pos: (3,) camera position in the map frame.
        cam_mat: (3, 3) camera-to-world rotation (MuJoCo's ``cam_xmat``).
        intrinsics: the camera's pinhole intrinsics.
        clean_depth: (H, W) noise-free z-depth of the same frame, metres.
        motion: how the sign's body stands off its map pose in the world (None: where the map says).
    """
    centre_world = target_centre(sign, motion)
    normal_world = _face_normal(sign, motion)
    world_to_opt, centre, corners, mask, behind = _project(centre_world, _moved(motion, _octagon_world(sign)),
                                                           cam_pos, cam_mat, intrinsics)
    if behind is not None:
        return behind
    facing = float(np.dot(cam_pos - centre_world, normal_world)) > 0
    if facing and (corners[:, 2] > 0.05).all():
        uv = intrinsics.project(corners)
        _fill(mask, uv)
        # The polygon's bounding box (a pixel of margin): the only part of the frame to search.
        (u0, v0), (u1, v1) = np.floor(uv.min(axis=0)).astype(int) - 1, np.ceil(uv.max(axis=0)).astype(int) + 2
        u0, v0, u1, v1 = max(u0, 0), max(v0, 0), min(u1, mask.shape[1]), min(v1, mask.shape[0])
        rows, cols = np.nonzero(mask[v0:v1, u0:u1]) if u0 < u1 and v0 < v1 else (np.empty(0, int),) * 2
        if len(rows):
            rows, cols = rows + v0, cols + u0
            # Depth of the sign's plane at each masked pixel: intersect the pixel's ray with it.
            normal_opt = world_to_opt @ normal_world
            rays = np.column_stack([(cols - intrinsics.cx) / intrinsics.fx,
                                    (rows - intrinsics.cy) / intrinsics.fy, np.ones(len(rows))])
            plane_z = float(normal_opt @ centre) / (rays @ normal_opt)
            visible = np.abs(clean_depth[rows, cols] - plane_z) < _DEPTH_TOLERANCE_M
            mask[rows[~visible], cols[~visible]] = False
    return _result(centre, mask)


def face_area_px(sign: StopSign, cam_pos: np.ndarray, cam_mat: np.ndarray, intrinsics: CameraIntrinsics,
                 motion: Motion | None = None) -> float:
    """Area in pixels of the sign's whole face projected on the image plane, as if nothing hid it
    and the image had no edges (0 when the camera sees its back or a corner is behind it); the
    share of it that ``sign_view``'s mask holds is how much of the sign a frame shows. ``motion``:
    how the sign's body stands off its map pose (None: where the map says)."""
    world_to_opt = _MJ_TO_OPTICAL @ cam_mat.T
    corners = (world_to_opt @ (_moved(motion, _octagon_world(sign)) - cam_pos).T).T
    facing = float(np.dot(cam_pos - target_centre(sign, motion), _face_normal(sign, motion))) > 0
    if not facing or (corners[:, 2] <= 0.05).any():
        return 0.0
    u, v = intrinsics.project(corners).T
    return float(0.5 * abs(np.dot(u, np.roll(v, 1)) - np.dot(v, np.roll(u, 1))))


def obstacle_view(obstacle, cam_pos: np.ndarray, cam_mat: np.ndarray,
                  intrinsics: CameraIntrinsics, clean_depth: np.ndarray, motion: Motion | None = None) -> SignView:
    """Ground truth of an obstacle crate, in the same form as a sign's.

    ``d_true`` is the depth of the centre of the crate's near face; the mask is the crate's
    projected outline where the rendered depth lies within the crate's depth span (so
    parts hidden behind something nearer are excluded). ``motion``: as :func:`sign_view`'s.
    """
    _, centre, corners, mask, behind = _project(_moved(motion, obstacle.centre), _moved(motion, obstacle.corners()),
                                                cam_pos, cam_mat, intrinsics)
    if behind is not None:
        return behind
    if (corners[:, 2] > 0.05).all():
        _fill(mask, cv2.convexHull(intrinsics.project(corners).astype(np.float32))[:, 0])
        z_lo, z_hi = corners[:, 2].min() - _DEPTH_TOLERANCE_M, corners[:, 2].max() + _DEPTH_TOLERANCE_M
        mask &= (clean_depth >= z_lo) & (clean_depth <= z_hi)
    return _result(centre, mask)


def with_centre_from(view: SignView, centre_world: np.ndarray, cam_pos: np.ndarray, cam_mat: np.ndarray) -> SignView:
    """``view`` (a frame's mask) with the target's centre seen from another camera pose.

    The camera's frame is older than the step when it runs slower than the loop: its mask
    belongs to the frame, but the target's depth and bearing to the car's pose now.
    """
    d_true, d_euclid, bearing = _centre_fields(_MJ_TO_OPTICAL @ cam_mat.T @ (centre_world - cam_pos))
    return SignView(d_true, d_euclid, bearing, view.mask, view.in_view)


def _centre_fields(centre: np.ndarray) -> tuple[float, float, float]:
    """(d_true, d_euclid, bearing) of a target centre in the optical frame; depth and bearing
    are NaN when it is behind the camera."""
    if centre[2] <= _BEHIND_M:
        return float("nan"), float(np.linalg.norm(centre)), float("nan")
    return float(centre[2]), float(np.linalg.norm(centre)), float(math.atan2(-centre[0], centre[2]))


def _project(centre_world, points_world, cam_pos, cam_mat, intrinsics):
    """Target centre and outline points in the optical frame, an empty mask, and the
    ready answer when the centre is behind the camera (else None)."""
    world_to_opt = _MJ_TO_OPTICAL @ cam_mat.T
    centre = world_to_opt @ (centre_world - cam_pos)
    mask = np.zeros((intrinsics.height, intrinsics.width), bool)
    behind = None
    if centre[2] <= _BEHIND_M:
        behind = SignView(*_centre_fields(centre), mask, False)
    return world_to_opt, centre, (world_to_opt @ (points_world - cam_pos).T).T, mask, behind


def _fill(mask: np.ndarray, uv: np.ndarray) -> None:
    """Fills the polygon ``uv`` (pixels) into ``mask`` with 1/16-pixel precision."""
    cv2.fillPoly(mask.view(np.uint8), [np.round(uv * 16).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=4)


def _result(centre: np.ndarray, mask: np.ndarray) -> SignView:
    return SignView(*_centre_fields(centre), mask, bool(mask.any()))
