"""Drives the QCar 2 model: Ackermann steering targets, wheel-speed commands, state, placement.

The physics (tyre contacts, differentials, the steering servo's lag, the motor torque
limit) lives in ``assets/qcar2_map/qcar2.xml``; this module maps the car-level command
(speed m/s, steering rad) onto the actuators and reads the car's state back. It resolves
every MuJoCo id once, by name, and never imports gymnasium.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.sim._gl import ensure_gl_backend

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["VehicleConfig", "VehicleState", "QCar2"]


@dataclass(frozen=True)
class VehicleConfig:
    """Command limits of the car.

    Attributes:
        max_speed_mps: largest forward speed command (rated top speed 3 m/s).
        max_reverse_mps: largest reverse speed command.
        max_steer_rad: steering limit at the wheels (+-30 deg).
    """

    max_speed_mps: float = 3.0
    max_reverse_mps: float = 1.0
    max_steer_rad: float = math.radians(30.0)

    def __post_init__(self) -> None:
        if not 0.0 < self.max_speed_mps <= 3.0:
            raise ValueError(f"max_speed_mps must be in (0, 3.0] m/s, got {self.max_speed_mps}")
        if not 0.0 <= self.max_reverse_mps <= 3.0:
            raise ValueError(f"max_reverse_mps must be in [0, 3.0] m/s, got {self.max_reverse_mps}")
        if not 0.0 < self.max_steer_rad <= math.radians(30.0) + 1e-9:
            raise ValueError(f"max_steer_rad must be in (0, 0.5236] rad, got {self.max_steer_rad}")


@dataclass(frozen=True)
class VehicleState:
    """The car's state in SI units.

    Attributes:
        x, y: position of the body origin (ground, midway between axles), map frame.
        yaw: heading, radians.
        speed: forward velocity in the body frame, m/s.
        lateral_speed: body-frame y velocity, m/s.
        yaw_rate: rad/s.
        steering: bicycle-equivalent front steering angle, radians.
        accel: longitudinal acceleration (body x, gravity removed), m/s^2.
    """

    x: float
    y: float
    yaw: float
    speed: float
    lateral_speed: float
    yaw_rate: float
    steering: float
    accel: float


class QCar2:
    """The car inside a compiled map model.

    Args:
        model: the compiled model (``racf.sim.world.scene.load_model``).
        config: command limits.
    """

    def __init__(self, model: mujoco.MjModel, config: VehicleConfig | None = None) -> None:
        self.model = model
        self.config = config or VehicleConfig()
        self.body_id = model.body("qcar").id
        self.root_qpos = model.joint("qcar_root").qposadr[0]
        self.root_qvel = model.joint("qcar_root").dofadr[0]
        wheels = ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")
        self.wheel_qvel = np.array([model.joint(w).dofadr[0] for w in wheels])
        self.steer_qpos = np.array([model.joint(j).qposadr[0] for j in ("steer_fl", "steer_fr")])
        self.drive_act = np.array([model.actuator(a).id for a in ("drive_front", "drive_rear")])
        self.steer_act = np.array([model.actuator(a).id for a in ("steer_fl", "steer_fr")])
        self.steer_actadr = np.array([model.actuator_actadr[i] for i in self.steer_act])
        front = model.body("knuckle_fl").pos
        rear = model.body("wheel_rl").pos
        self.wheelbase_m = float(front[0] - rear[0])
        self.track_m = float(front[1] - model.body("knuckle_fr").pos[1])
        self.wheel_radius_m = float(model.geom("wheel_fl").size[0])
        self._vel_sensor = model.sensor("imu_vel").adr[0]
        self._gyro_sensor = model.sensor("imu_gyro").adr[0]
        self._acc_sensor = model.sensor("imu_acc").adr[0]

    # -- commands -----------------------------------------------------------------------
    def ackermann(self, steer: float) -> tuple[float, float]:
        """(left, right) wheel angles in radians for a bicycle-equivalent angle ``steer``."""
        if abs(steer) < 1e-9:
            return 0.0, 0.0
        radius = self.wheelbase_m / math.tan(steer)  # signed turning radius of the axle centre
        half = self.track_m / 2
        return (math.atan(self.wheelbase_m / (radius - half)), math.atan(self.wheelbase_m / (radius + half)))

    def apply(self, data: mujoco.MjData, speed_cmd: float, steer_cmd: float) -> None:
        """Writes the actuator controls for a speed (m/s) and steering (rad) command."""
        speed = float(np.clip(speed_cmd, -self.config.max_reverse_mps, self.config.max_speed_mps))
        steer = float(np.clip(steer_cmd, -self.config.max_steer_rad, self.config.max_steer_rad))
        data.ctrl[self.drive_act] = speed / self.wheel_radius_m
        data.ctrl[self.steer_act] = self.ackermann(steer)

    # -- state --------------------------------------------------------------------------
    def steering_angle(self, data: mujoco.MjData) -> float:
        """Bicycle-equivalent angle of the two front wheels: cot = mean of the cotangents."""
        left, right = (float(data.qpos[i]) for i in self.steer_qpos)
        tl, tr = math.tan(left), math.tan(right)
        if abs(tl) < 1e-6 or abs(tr) < 1e-6 or tl * tr < 0:
            return 0.5 * (left + right)
        return math.atan(2.0 / (1.0 / tl + 1.0 / tr))

    def state(self, data: mujoco.MjData) -> VehicleState:
        q = data.qpos[self.root_qpos : self.root_qpos + 7]
        w, x, y, z = q[3:7]
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        vel = data.sensordata[self._vel_sensor : self._vel_sensor + 3]
        gyro = data.sensordata[self._gyro_sensor : self._gyro_sensor + 3]
        acc = data.sensordata[self._acc_sensor : self._acc_sensor + 3]
        return VehicleState(float(q[0]), float(q[1]), yaw, float(vel[0]), float(vel[1]),
                            float(gyro[2]), self.steering_angle(data), float(acc[0]))

    def camera_pose(self, model: mujoco.MjModel, data: mujoco.MjData, name: str = "d435"
                    ) -> tuple[np.ndarray, np.ndarray]:
        """(position (3,), rotation (3, 3) camera-to-world) of a car camera, map frame."""
        cam = model.camera(name).id
        return data.cam_xpos[cam].copy(), data.cam_xmat[cam].reshape(3, 3).copy()

    def front_bumper(self, data: mujoco.MjData) -> np.ndarray:
        """(2,) front bumper centre in the map frame."""
        return data.site("front_bumper").xpos[:2].copy()

    # -- placement ----------------------------------------------------------------------
    def place(self, data: mujoco.MjData, x: float, y: float, yaw: float,
              speed: float = 0.0, steer: float = 0.0) -> None:
        """Puts the car at a pose, resting on its wheels, already moving at ``speed``."""
        q = self.root_qpos
        data.qpos[q : q + 3] = (x, y, 0.0)
        data.qpos[q + 3 : q + 7] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        v = self.root_qvel
        data.qvel[v : v + 3] = (speed * math.cos(yaw), speed * math.sin(yaw), 0.0)
        data.qvel[v + 3 : v + 6] = 0.0
        data.qvel[self.wheel_qvel] = speed / self.wheel_radius_m
        left, right = self.ackermann(steer)
        data.qpos[self.steer_qpos] = (left, right)
        data.act[self.steer_actadr] = (left, right)
        self.apply(data, speed, steer)
