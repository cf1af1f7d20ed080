# The package's names, for type checkers and editors, and for lazy_loader, which imports each on
# first use (racf's __init__.py reads this file): the one list of what the package exports.
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

__all__ = [
    "BrakeDecision", "BrakingConfig", "CameraModel", "DepthDistance", "Detection", "DetectorConfig",
    "DistanceEKF", "DistanceEstimator", "EKFConfig", "EKFEstimator", "LidarTargetConfig", "LidarTargetState",
    "LidarTargetTracker", "ObstacleDetector", "ObstacleDetectorConfig", "Perception", "PerceptionSample",
    "Phase", "PoseFilter", "PoseFilterConfig", "RawDepthEstimator", "RouteFollower", "scan_points",
    "segment_scan", "SizeDistance", "SpeedPI", "SpeedPIConfig", "SpeedProfile", "StanleyConfig", "StanleyController",
    "StopSignBraker", "StopSignDetector", "wrap_angle",
]
