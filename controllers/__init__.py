"""Perception and control that see observations only (no simulator imports)."""

from racf.controllers.braking import BrakeDecision, BrakingConfig, Phase, StopSignBraker
from racf.controllers.detector import Detection, DetectorConfig, StopSignDetector
from racf.controllers.distance import CameraModel, DepthDistance
from racf.controllers.lidar_segmentation import scan_points, segment_scan
from racf.controllers.lidar_target import LidarTargetConfig, LidarTargetState, LidarTargetTracker
from racf.controllers.ekf import DistanceEKF, EKFConfig
from racf.controllers.localisation import PoseFilter, PoseFilterConfig, wrap_angle
from racf.controllers.estimators import DistanceEstimator, EKFEstimator, RawDepthEstimator
from racf.controllers.obstacle_detector import ObstacleDetector, ObstacleDetectorConfig
from racf.controllers.lane_follower import RouteFollower, StanleyConfig, StanleyController
from racf.controllers.perception import Perception, PerceptionSample
from racf.controllers.size_distance import SizeDistance
from racf.controllers.speed import SpeedPI, SpeedPIConfig, SpeedProfile

__all__ = [
    "BrakeDecision", "BrakingConfig", "CameraModel", "DepthDistance", "Detection", "DetectorConfig",
    "DistanceEKF", "DistanceEstimator", "EKFConfig", "EKFEstimator", "LidarTargetConfig", "LidarTargetState",
    "LidarTargetTracker", "ObstacleDetector", "ObstacleDetectorConfig", "Perception", "PerceptionSample",
    "Phase", "PoseFilter", "PoseFilterConfig", "RawDepthEstimator", "RouteFollower", "scan_points",
    "segment_scan", "SizeDistance", "SpeedPI", "SpeedPIConfig", "SpeedProfile", "StanleyConfig", "StanleyController",
    "StopSignBraker", "StopSignDetector", "wrap_angle",
]
