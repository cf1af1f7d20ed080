"""Perception and control that see observations only (no simulator imports)."""

from controllers.braking import BrakeDecision, BrakingConfig, Phase, StopSignBraker
from controllers.detector import Detection, DetectorConfig, StopSignDetector
from controllers.distance import CameraModel, DepthDistance, LidarReference, LidarReferenceConfig
from controllers.estimators import DistanceEstimator, RawDepthEstimator
from controllers.obstacle_detector import ObstacleDetector, ObstacleDetectorConfig
from controllers.lane_follower import RouteFollower, StanleyConfig, StanleyController
from controllers.perception import Perception, PerceptionSample
from controllers.speed import SpeedPI, SpeedPIConfig, SpeedProfile

__all__ = [
    "BrakeDecision", "BrakingConfig", "CameraModel", "DepthDistance", "Detection", "DetectorConfig",
    "DistanceEstimator", "LidarReference", "LidarReferenceConfig", "ObstacleDetector", "ObstacleDetectorConfig", "Perception", "PerceptionSample", "Phase",
    "RawDepthEstimator", "RouteFollower", "SpeedPI", "SpeedPIConfig", "SpeedProfile", "StanleyConfig",
    "StanleyController", "StopSignBraker", "StopSignDetector",
]
