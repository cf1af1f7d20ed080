"""The car's sensors, one per module, all with ``space`` metadata, ``reset(rng)`` and ``read(model, data, rng)``."""

from typing import TYPE_CHECKING

import lazy_loader

# Each name is imported on first use (SPEC 1), as __init__.pyi lists them: importing the package costs
# nothing, so the command line's help never waits for torch, scikit-learn or the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

if TYPE_CHECKING:  # the same names for editors that read no stub (jedi); a test holds the two lists equal
    from .base import TIMESTAMP_FIELDS, Sensor, SensorRate
    from .calibration import CarBuild, car_build
    from .camera import CameraConfig, CameraIntrinsics, DepthCamera, RGBCamera, RGBDCameraRig
    from .lidar import Lidar2D, LidarConfig
    from .localiser import LocalisationFix, LocaliserConfig
    from .state import STATE_FIELDS, OdometryConfig, VehicleStateSensor
