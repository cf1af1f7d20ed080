"""Perception and control that see observations only (no simulator imports)."""

from controllers.braking import BrakeDecision, BrakingConfig, Phase, StopSignBraker
from controllers.detector import Detection, DetectorConfig, StopSignDetector
from controllers.distance import CameraModel, DepthDistance
from controllers.lidar_segmentation import scan_points, segment_scan
from controllers.lidar_target import LidarTargetConfig, LidarTargetState, LidarTargetTracker
from controllers.ekf import DistanceEKF, EKFConfig
from controllers.localisation import PoseFilter, PoseFilterConfig, wrap_angle
from controllers.estimators import DistanceEstimator, EKFEstimator, RawDepthEstimator
from controllers.obstacle_detector import ObstacleDetector, ObstacleDetectorConfig
from controllers.lane_follower import RouteFollower, StanleyConfig, StanleyController
from controllers.perception import Perception, PerceptionSample
from controllers.speed import SpeedPI, SpeedPIConfig, SpeedProfile

__all__ = [
    "BrakeDecision", "BrakingConfig", "CameraModel", "DepthDistance", "Detection", "DetectorConfig",
    "DistanceEKF", "DistanceEstimator", "EKFConfig", "EKFEstimator", "LidarTargetConfig", "LidarTargetState",
    "LidarTargetTracker", "ObstacleDetector", "ObstacleDetectorConfig", "Perception", "PerceptionSample",
    "Phase", "PoseFilter", "PoseFilterConfig", "RawDepthEstimator", "RouteFollower", "scan_points",
    "segment_scan", "SpeedPI", "SpeedPIConfig", "SpeedProfile", "StanleyConfig", "StanleyController",
    "StopSignBraker", "StopSignDetector", "wrap_angle",
]
