"""The car's sensors, one per module, all with ``space`` metadata and ``read(model, data, rng)``."""

from sim.sensors.base import Sensor, SensorRate
from sim.sensors.camera import CameraConfig, CameraIntrinsics, DepthCamera, RGBCamera, RGBDCameraRig
from sim.sensors.lidar import Lidar2D, LidarConfig
from sim.sensors.state import STATE_FIELDS, VehicleStateSensor

__all__ = [
    "Sensor", "SensorRate", "CameraConfig", "CameraIntrinsics", "DepthCamera", "RGBCamera",
    "RGBDCameraRig", "Lidar2D", "LidarConfig", "STATE_FIELDS", "VehicleStateSensor",
]
