"""Perception and control that see observations only (no simulator imports)."""

from typing import TYPE_CHECKING

import lazy_loader

# Each name is imported on first use (SPEC 1), as __init__.pyi lists them: importing the package costs
# nothing, so the command line's help never waits for torch, scikit-learn or the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

if TYPE_CHECKING:  # the same names for editors that read no stub (jedi); a test holds the two lists equal
    from .braking import BrakeDecision, BrakingConfig, Phase, StopSignBraker
    from .detector import Detection, DetectorConfig, StopSignDetector
    from .distance import CameraModel, DepthDistance
    from .lidar_segmentation import scan_points, segment_scan
    from .lidar_target import LidarTargetConfig, LidarTargetState, LidarTargetTracker
    from .ekf import DistanceEKF, EKFConfig
    from .localisation import PoseFilter, PoseFilterConfig, wrap_angle
    from .estimators import DistanceEstimator, EKFEstimator, RawDepthEstimator
    from .obstacle_detector import ObstacleDetector, ObstacleDetectorConfig
    from .lane_follower import RouteFollower, StanleyConfig, StanleyController
    from .perception import Perception, PerceptionSample
    from .size_distance import SizeDistance
    from .speed import SpeedPI, SpeedPIConfig, SpeedProfile
