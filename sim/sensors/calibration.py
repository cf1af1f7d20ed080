"""The car's build as the spec sheet gives it to the car's software: where the camera, the LiDAR,
the front bumper and the rear axle sit on the body, read from the car's MJCF (the model the
simulator drives), and the D435's intrinsics at a resolution.

The simulator owns this knowledge; the experiments hand it to the car as its calibration, the
way a real car's software is configured from its build, never from the running simulation.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from racf.sim.sensors.camera import CameraIntrinsics

__all__ = ["CarBuild", "car_build"]


@dataclass(frozen=True)
class CarBuild:
    """The mounts on the body (x forward, y left, m) and the colour camera's intrinsics."""

    intrinsics: CameraIntrinsics
    camera_xy_m: tuple[float, float]
    bumper_x_m: float
    rear_axle_x_m: float
    lidar_xy_m: tuple[float, float]
    camera_height_m: float = 0.172
    lidar_height_m: float = 0.0


@lru_cache(maxsize=8)
def car_build(width_px: int, height_px: int) -> CarBuild:
    """The QCar 2's build with its camera at ``width_px`` x ``height_px``."""
    import mujoco

    from racf.sim.world.scene import ASSETS_DIR

    car = (ASSETS_DIR / "qcar2.xml").read_bytes()
    model = mujoco.MjModel.from_xml_string('<mujoco model="qcar2"><include file="qcar2.xml"/></mujoco>',
                                           {"qcar2.xml": car})
    camera, lidar = model.camera("d435").pos, model.site("lidar").pos
    return CarBuild(CameraIntrinsics.d435_colour(width_px, height_px), (float(camera[0]), float(camera[1])),
                    float(model.site("front_bumper").pos[0]), float(model.body("wheel_rl").pos[0]),
                    (float(lidar[0]), float(lidar[1])), float(camera[2]), float(lidar[2]))
