"""The car's sensors, one per module, all with ``space`` metadata, ``reset(rng)`` and ``read(model, data, rng)``."""

import lazy_loader

# Each name is imported on first use (SPEC 1): a command's --help never waits for the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "base": ["TIMESTAMP_FIELDS", "Sensor", "SensorRate"],
    "calibration": ["CarBuild", "car_build"],
    "camera": ["CameraConfig", "CameraIntrinsics", "DepthCamera", "RGBCamera", "RGBDCameraRig"],
    "lidar": ["Lidar2D", "LidarConfig"],
    "localiser": ["LocalisationFix", "LocaliserConfig"],
    "state": ["STATE_FIELDS", "OdometryConfig", "VehicleStateSensor"],
})
