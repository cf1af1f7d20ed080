"""Configuration of the QCar 2 env: one frozen dataclass, validated, unknown keys rejected."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from racf.sim.radio.channel import RadioConfig
from racf.sim.sensors.a2m12 import A2M12Config
from racf.sim.sensors.camera import CameraConfig
from racf.sim.sensors.lidar import LidarConfig
from racf.sim.sensors.localiser import LOCALISATIONS, LocaliserConfig
from racf.sim.sensors.state import OdometryConfig
from racf.sim.vehicle.qcar2 import VehicleConfig
from racf.sim.world.stop_signs import SignGeometry

__all__ = ["EnvConfig", "RESET_OPTIONS", "LOCALISATIONS", "SENSOR_PROFILES"]

#: Sensor profiles and what each sets, unless the config says otherwise: ``qcar2``, the
#: car as it is (the A2M12 through Quanser's driver, the camera at 30 Hz, the car's own
#: localisation); ``ideal``, the sensors of env v2 (a one-instant 360-beam LiDAR, every
#: sensor at 50 Hz, the true pose), for ablations.
SENSOR_PROFILES: dict[str, dict[str, Any]] = {
    "qcar2": {"lidar_model": "a2m12", "camera_hz": 30.0, "localisation": "qcar2"},
    "ideal": {"lidar_model": "ideal", "camera_hz": 50.0, "localisation": "true"},
}


#: Keys ``reset(options=...)`` accepts.
RESET_OPTIONS = ("sign", "obstacle", "cruise_speed", "run_up_m", "route", "start_s_m", "lateral_offset_m",
                 "heading_error_rad", "crate")


@dataclass(frozen=True)
class EnvConfig:
    """Settings of ``RACF/QCar2-v4``.

    Attributes:
        sensor_profile: one of ``SENSOR_PROFILES`` (``qcar2``, the default, or ``ideal``);
            it fills in ``camera_hz`` and ``localisation`` where they are not given, and
            picks the LiDAR: the swept A2M12 (``a2m12``) or the ideal one (``lidar``).
        control_hz: control (and default sensor) rate.
        physics_dt_s: MuJoCo time step; ``1/control_hz`` must be a whole number of steps.
        camera, vehicle: component configs.
        lidar: the ideal LiDAR's settings (profile ``ideal``).
        a2m12: the A2M12's and its driver's settings (profile ``qcar2``).
        sign: the stop signs' plate height and pole (a scenario parameter).
        localisation: where the ``gps`` fix comes from, one of ``LOCALISATIONS``
            (None: the profile's).
        localiser: the ``qcar2`` fix's drift and noise.
        odometry: the encoder's and the IMU's quantisation, noise and biases.
        camera_hz: frames a second (None: the profile's, 30 or 50), at most ``control_hz``;
            a frame is taken at the physics step its time falls in and held until the next.
        lidar_hz, state_hz: the LiDAR's revolutions and the state sensors' readings a
            second; each must divide ``control_hz`` into whole steps. The LiDAR turns at the
            A2M12's 10 Hz by default; the localiser's fixes come one per scan.
        cruise_speeds_mps: speeds ``reset`` draws from when no ``cruise_speed`` is given.
        max_episode_s: episode time limit (truncation).
        off_road_m: lateral distance from the route's lane centre that ends the episode.
        render_width, render_height: size of ``render()`` frames.
        world: a scenario's world managers (``racf.sim.world.manager.WorldManager``): bodies added to
            the map and driven at each reset and physics step; each may read one more reset option
            and log its own ground-truth columns.
        radio: the vehicle-to-vehicle radio's rate, latency, loss and range (``racf.sim.radio``): what
            a world manager's vehicles broadcast reaches the car through it.
    """

    sensor_profile: str = "qcar2"
    control_hz: float = 50.0
    physics_dt_s: float = 0.002
    camera: CameraConfig = field(default_factory=CameraConfig)
    lidar: LidarConfig = field(default_factory=LidarConfig)
    a2m12: A2M12Config = field(default_factory=A2M12Config)
    vehicle: VehicleConfig = field(default_factory=VehicleConfig)
    sign: SignGeometry = field(default_factory=SignGeometry)
    localisation: str | None = None
    localiser: LocaliserConfig = field(default_factory=LocaliserConfig)
    odometry: OdometryConfig = field(default_factory=OdometryConfig)
    camera_hz: float | None = None
    lidar_hz: float = 10.0
    state_hz: float = 50.0
    cruise_speeds_mps: tuple[float, ...] = (1.0, 1.5, 2.0)
    max_episode_s: float = 20.0
    off_road_m: float = 0.30
    render_width: int = 640
    render_height: int = 480
    world: tuple = ()
    radio: RadioConfig = field(default_factory=RadioConfig)

    def __post_init__(self) -> None:
        if not isinstance(self.sensor_profile, str) or self.sensor_profile not in SENSOR_PROFILES:
            raise ValueError(f"sensor_profile must be one of {tuple(SENSOR_PROFILES)}, got {self.sensor_profile!r}")
        profile = SENSOR_PROFILES[self.sensor_profile]
        for name in ("camera_hz", "localisation"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, profile[name])
        if not 1.0 <= self.control_hz <= 500.0:
            raise ValueError(f"control_hz must be in [1, 500] Hz, got {self.control_hz}")
        if not 1e-4 <= self.physics_dt_s <= 0.01:
            raise ValueError(f"physics_dt_s must be in [0.0001, 0.01] s, got {self.physics_dt_s}")
        if abs(self.substeps * self.physics_dt_s * self.control_hz - 1.0) > 1e-6:
            raise ValueError(f"1/control_hz = {1 / self.control_hz} s must be a whole number of physics_dt_s = {self.physics_dt_s} s")
        if self.localisation not in LOCALISATIONS:
            raise ValueError(f"localisation must be one of {LOCALISATIONS}, got {self.localisation!r}")
        if not (isinstance(self.camera_hz, (int, float)) and 0 < self.camera_hz <= self.control_hz):
            raise ValueError(f"camera_hz must be in (0, control_hz={self.control_hz}] Hz, got {self.camera_hz!r}")
        for name in ("lidar_hz", "state_hz"):
            rate = getattr(self, name)
            if not (0 < rate <= self.control_hz) or abs(self.control_hz / rate - round(self.control_hz / rate)) > 1e-6:
                raise ValueError(f"{name} must divide control_hz={self.control_hz} into whole steps (e.g. 50, 25, 10), got {rate}")
        if not self.cruise_speeds_mps or not all(0.1 <= v <= self.vehicle.max_speed_mps for v in self.cruise_speeds_mps):
            raise ValueError(f"cruise_speeds_mps must be non-empty, each in [0.1, {self.vehicle.max_speed_mps}] m/s, got {self.cruise_speeds_mps}")
        if not 0.1 <= self.max_episode_s <= 3600:
            raise ValueError(f"max_episode_s must be in [0.1, 3600] s, got {self.max_episode_s}")
        if not 0.05 <= self.off_road_m <= 2.0:
            raise ValueError(f"off_road_m must be in [0.05, 2] m, got {self.off_road_m}")
        _check_world(self.world)
        if not (16 <= self.render_width <= 1280 and 12 <= self.render_height <= 960):
            raise ValueError(f"render size must be within 1280x960 px, got {self.render_width}x{self.render_height}")

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return int(round(1.0 / (self.control_hz * self.physics_dt_s)))

    @property
    def lidar_model(self) -> str:
        """``a2m12`` (the swept A2M12 through Quanser's driver) or ``ideal`` (one instant, 360 beams)."""
        return SENSOR_PROFILES[self.sensor_profile]["lidar_model"]

    def decimation(self, rate_hz: float) -> int:
        """Control steps between two readings of a sensor running at ``rate_hz``."""
        return int(round(self.control_hz / rate_hz))

    @classmethod
    def from_kwargs(cls, **kwargs: Any) -> "EnvConfig":
        """Builds a config from flat keyword arguments.

        Top-level fields by name; component fields with a prefix: ``camera_width=160``,
        ``lidar_n_beams=720``, ``a2m12_sub_rays=5``, ``vehicle_max_speed_mps=2.0``,
        ``sign_plate_bottom_m=0.21``, ``localiser_noise_xy_m=0.02``, ``odometry_exact=True``.

        Raises:
            ValueError: for an unknown key (naming it and listing the allowed ones) or an
                out-of-range value.
        """
        top = {f.name for f in dataclasses.fields(cls)}
        parts = {"camera": CameraConfig, "lidar": LidarConfig, "a2m12": A2M12Config, "vehicle": VehicleConfig,
                 "sign": SignGeometry, "localiser": LocaliserConfig, "odometry": OdometryConfig}
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


def _check_world(world: Any) -> None:
    from racf.sim.world.manager import WorldManager

    if not isinstance(world, tuple) or not all(isinstance(m, WorldManager) for m in world):
        raise ValueError(f"world must be a tuple of racf.sim.world.manager.WorldManager, got {world!r}")
    options = [m.option for m in world if m.option]
    taken = sorted({o for o in options if options.count(o) > 1 or o in RESET_OPTIONS})
    if taken:
        raise ValueError(f"world managers read reset option(s) {taken} that another part reads; give each its own")
    columns = [c.name for m in world for c in m.columns()]
    twice = sorted({c for c in columns if columns.count(c) > 1})
    if twice:
        raise ValueError(f"world managers log column(s) {twice} that another manager logs; give each its own")
