"""The QCar 2's physical facts both sides of an episode share, and the one definition of the clear gap.

The supervisor (the car's side) and the referee (the truth's side) must measure the same gap to the
car ahead, or a margin the supervisor keeps can be less than the referee's. The **clear gap** is the
distance from the centre of the ego car's front bumper to the centre of the target's rear face.

- The referee measures it from the two bodies' poses (:func:`clear_gap_of_poses`).
- The supervisor measures it from the camera (:func:`clear_gap_m`): the camera's straight-line
  distance to the rear, which its witnesses read (those that read along the camera's axis taken to
  the lane point at that depth first), less the bumper's lead on the camera. The bumper lies on the
  way from the camera, so by the triangle inequality the camera's distance less the bumper's lead is
  never more than the bumper's: the supervisor's gap is never the larger of the two. (Along the axis
  alone it would be smaller still: in a bend by r (1 - cos bearing), 0.15 m at 0.73 m and 37 degrees,
  and the stop rule braked hard for nothing.)
"""

from __future__ import annotations

import numpy as np

__all__ = ["QCAR2_BOX_M", "clear_gap_m", "clear_gap_of_poses"]

#: A QCar 2's box: length, width, height, m (its MJCF body's extent).
QCAR2_BOX_M = (0.425, 0.192, 0.20)


def clear_gap_m(camera_distance_m, bumper_ahead_of_camera_m: float):
    """The clear gap from the camera, m: the camera's straight-line distance to the target's rear less
    the bumper's lead on the camera (scalars or arrays)."""
    return camera_distance_m - bumper_ahead_of_camera_m


def clear_gap_of_poses(ego_x, ego_y, ego_yaw, lead_x, lead_y, lead_yaw, bumper_x_m: float,
                       lead_length_m: float = QCAR2_BOX_M[0]):
    """The clear gap from both bodies' poses (map frame; scalars or arrays), m: from the ego's front
    bumper centre (``bumper_x_m`` ahead of its origin) to the centre of the lead's rear face."""
    front_x, front_y = ego_x + bumper_x_m * np.cos(ego_yaw), ego_y + bumper_x_m * np.sin(ego_yaw)
    rear_x = lead_x - 0.5 * lead_length_m * np.cos(lead_yaw)
    rear_y = lead_y - 0.5 * lead_length_m * np.sin(lead_yaw)
    return np.hypot(rear_x - front_x, rear_y - front_y)
