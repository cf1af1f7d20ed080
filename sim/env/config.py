"""Configuration of the QCar 2 env: one frozen dataclass, validated, unknown keys rejected."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from sim.sensors.camera import CameraConfig
from sim.sensors.lidar import LidarConfig
from sim.sensors.localiser import LOCALISATIONS, LocaliserConfig
from sim.sensors.state import OdometryConfig
from sim.vehicle.qcar2 import VehicleConfig

__all__ = ["EnvConfig", "RESET_OPTIONS", "LOCALISATIONS"]


#: Keys ``reset(options=...)`` accepts.
RESET_OPTIONS = ("sign", "obstacle", "cruise_speed", "run_up_m", "route", "start_s_m", "lateral_offset_m",
                 "heading_error_rad", "crate")


@dataclass(frozen=True)
class EnvConfig:
    """Settings of ``RACF/QCar2-v2``.

    Attributes:
        control_hz: control (and default sensor) rate.
        physics_dt_s: MuJoCo time step; ``1/control_hz`` must be a whole number of steps.
        camera, lidar, vehicle: component configs.
        localisation: where the ``gps`` fix comes from, one of ``LOCALISATIONS``.
        localiser: the ``qcar2`` fix's drift and noise.
        odometry: the encoder's and the IMU's quantisation, noise and biases.
        camera_hz, lidar_hz, state_hz: sensor rates; a sensor between readings holds its
            last one. Each must divide ``control_hz`` into whole steps. The LiDAR scans at
            the A2M12's 10 Hz by default.
        cruise_speeds_mps: speeds ``reset`` draws from when no ``cruise_speed`` is given.
        max_episode_s: episode time limit (truncation).
        off_road_m: lateral distance from the route's lane centre that ends the episode.
        render_width, render_height: size of ``render()`` frames.
    """

    control_hz: float = 50.0
    physics_dt_s: float = 0.002
    camera: CameraConfig = field(default_factory=CameraConfig)
    lidar: LidarConfig = field(default_factory=LidarConfig)
    vehicle: VehicleConfig = field(default_factory=VehicleConfig)
    localisation: str = "qcar2"
    localiser: LocaliserConfig = field(default_factory=LocaliserConfig)
    odometry: OdometryConfig = field(default_factory=OdometryConfig)
    camera_hz: float = 50.0
    lidar_hz: float = 10.0
    state_hz: float = 50.0
    cruise_speeds_mps: tuple[float, ...] = (1.0, 1.5, 2.0)
    max_episode_s: float = 20.0
    off_road_m: float = 0.30
    render_width: int = 640
    render_height: int = 480

    def __post_init__(self) -> None:
        if not 1.0 <= self.control_hz <= 500.0:
            raise ValueError(f"control_hz must be in [1, 500] Hz, got {self.control_hz}")
        if not 1e-4 <= self.physics_dt_s <= 0.01:
            raise ValueError(f"physics_dt_s must be in [0.0001, 0.01] s, got {self.physics_dt_s}")
        if abs(self.substeps * self.physics_dt_s * self.control_hz - 1.0) > 1e-6:
            raise ValueError(f"1/control_hz = {1 / self.control_hz} s must be a whole number of physics_dt_s = {self.physics_dt_s} s")
        if self.localisation not in LOCALISATIONS:
            raise ValueError(f"localisation must be one of {LOCALISATIONS}, got {self.localisation!r}")
        for name in ("camera_hz", "lidar_hz", "state_hz"):
            rate = getattr(self, name)
            if not (0 < rate <= self.control_hz) or abs(self.control_hz / rate - round(self.control_hz / rate)) > 1e-6:
                raise ValueError(f"{name} must divide control_hz={self.control_hz} into whole steps (e.g. 50, 25, 10), got {rate}")
        if not self.cruise_speeds_mps or not all(0.1 <= v <= self.vehicle.max_speed_mps for v in self.cruise_speeds_mps):
            raise ValueError(f"cruise_speeds_mps must be non-empty, each in [0.1, {self.vehicle.max_speed_mps}] m/s, got {self.cruise_speeds_mps}")
        if not 0.1 <= self.max_episode_s <= 3600:
            raise ValueError(f"max_episode_s must be in [0.1, 3600] s, got {self.max_episode_s}")
        if not 0.05 <= self.off_road_m <= 2.0:
            raise ValueError(f"off_road_m must be in [0.05, 2] m, got {self.off_road_m}")
        if not (16 <= self.render_width <= 1280 and 12 <= self.render_height <= 960):
            raise ValueError(f"render size must be within 1280x960 px, got {self.render_width}x{self.render_height}")

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return int(round(1.0 / (self.control_hz * self.physics_dt_s)))

    def decimation(self, rate_hz: float) -> int:
        """Control steps between two readings of a sensor running at ``rate_hz``."""
        return int(round(self.control_hz / rate_hz))

    @classmethod
    def from_kwargs(cls, **kwargs: Any) -> "EnvConfig":
        """Builds a config from flat keyword arguments.

        Top-level fields by name; component fields with a prefix: ``camera_width=160``,
        ``lidar_n_beams=720``, ``vehicle_max_speed_mps=2.0``, ``localiser_noise_xy_m=0.02``,
        ``odometry_exact=True``.

        Raises:
            ValueError: for an unknown key (naming it and listing the allowed ones) or an
                out-of-range value.
        """
        top = {f.name for f in dataclasses.fields(cls)}
        parts = {"camera": CameraConfig, "lidar": LidarConfig, "vehicle": VehicleConfig,
                 "localiser": LocaliserConfig, "odometry": OdometryConfig}
        values: dict[str, Any] = {}
        nested: dict[str, dict[str, Any]] = {p: {} for p in parts}
        for key, value in kwargs.items():
            prefix = next((p for p in parts if key.startswith(p + "_")), None)
            if key in top:
                values[key] = value
            elif prefix and key[len(prefix) + 1:] in {f.name for f in dataclasses.fields(parts[prefix])}:
                nested[prefix][key[len(prefix) + 1:]] = value
            else:
                allowed = sorted(top - set(parts)) + sorted(
                    f"{p}_{f.name}" for p, c in parts.items() for f in dataclasses.fields(c))
                raise ValueError(f"unknown env option {key!r}; allowed: {', '.join(allowed)}")
        for prefix, cls_ in parts.items():
            if nested[prefix]:
                base = values.get(prefix, cls_())
                values[prefix] = dataclasses.replace(base, **nested[prefix])
        if "cruise_speeds_mps" in values:
            values["cruise_speeds_mps"] = tuple(float(v) for v in values["cruise_speeds_mps"])
        return cls(**values)
