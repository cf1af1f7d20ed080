"""The QCar 2's physical facts both sides of an episode share, and the one definition of the clear gap.

The supervisor (the car's side) and the referee (the truth's side) must measure the same gap to the
car ahead, or a margin the supervisor keeps can be less than the referee's: the **clear gap** is the
camera's distance to the target's rear face, along the camera's optical axis, less how far the front
bumper sits ahead of the camera. The supervisor feeds it its vouched distance; the referee the true
one (:func:`camera_distance_to_rear`, from the two bodies' poses).
"""

from __future__ import annotations

import numpy as np

__all__ = ["QCAR2_BOX_M", "clear_gap_m", "camera_distance_to_rear"]

#: A QCar 2's box: length, width, height, m (its MJCF body's extent).
QCAR2_BOX_M = (0.425, 0.192, 0.20)


def clear_gap_m(camera_distance_m, bumper_ahead_of_camera_m: float):
    """The clear gap, m: the camera distance to the target's rear less the bumper's lead on the camera
    (scalars or arrays)."""
    return camera_distance_m - bumper_ahead_of_camera_m


def camera_distance_to_rear(ego_x, ego_y, ego_yaw, lead_x, lead_y, lead_yaw, camera_xy_m: tuple[float, float],
                            lead_length_m: float = QCAR2_BOX_M[0]):
    """The camera's distance to the centre of the lead's rear face along the camera's optical axis, m,
    from both bodies' poses (map frame; scalars or arrays)."""
    c, s = np.cos(ego_yaw), np.sin(ego_yaw)
    cam_x = ego_x + c * camera_xy_m[0] - s * camera_xy_m[1]
    cam_y = ego_y + s * camera_xy_m[0] + c * camera_xy_m[1]
    rear_x = lead_x - 0.5 * lead_length_m * np.cos(lead_yaw)
    rear_y = lead_y - 0.5 * lead_length_m * np.sin(lead_yaw)
    return (rear_x - cam_x) * c + (rear_y - cam_y) * s
