# The package's names, for type checkers and editors, and for lazy_loader, which imports each on
# first use (racf's __init__.py reads this file): the one list of what the package exports.
from .base import TIMESTAMP_FIELDS, Sensor, SensorRate
from .calibration import CarBuild, car_build
from .camera import CameraConfig, CameraIntrinsics, DepthCamera, RGBCamera, RGBDCameraRig
from .lidar import Lidar2D, LidarConfig
from .localiser import LocalisationFix, LocaliserConfig
from .state import STATE_FIELDS, OdometryConfig, VehicleStateSensor

__all__ = [
    "Sensor", "SensorRate", "TIMESTAMP_FIELDS", "CameraConfig", "CameraIntrinsics", "DepthCamera", "RGBCamera",
    "RGBDCameraRig", "Lidar2D", "LidarConfig", "LocaliserConfig", "LocalisationFix",
    "STATE_FIELDS", "OdometryConfig", "VehicleStateSensor", "CarBuild", "car_build",
]
