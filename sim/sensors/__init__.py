"""The car's sensors, one per module, all with ``space`` metadata, ``reset(rng)`` and ``read(model, data, rng)``."""

from racf.sim.sensors.base import TIMESTAMP_FIELDS, Sensor, SensorRate
from racf.sim.sensors.calibration import CarBuild, car_build
from racf.sim.sensors.camera import CameraConfig, CameraIntrinsics, DepthCamera, RGBCamera, RGBDCameraRig
from racf.sim.sensors.lidar import Lidar2D, LidarConfig
from racf.sim.sensors.localiser import LocalisationFix, LocaliserConfig
from racf.sim.sensors.state import STATE_FIELDS, OdometryConfig, VehicleStateSensor

__all__ = [
    "Sensor", "SensorRate", "TIMESTAMP_FIELDS", "CameraConfig", "CameraIntrinsics", "DepthCamera", "RGBCamera",
    "RGBDCameraRig", "Lidar2D", "LidarConfig", "LocaliserConfig", "LocalisationFix",
    "STATE_FIELDS", "OdometryConfig", "VehicleStateSensor", "CarBuild", "car_build",
]
