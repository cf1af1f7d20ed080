"""Perception and control that see observations only (no simulator imports)."""

import lazy_loader

# Each name is imported on first use (SPEC 1): importing the package costs nothing, so the
# command line's help never waits for torch or scikit-learn.
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "braking": ["BrakeDecision", "BrakingConfig", "Phase", "StopSignBraker"],
    "detector": ["Detection", "DetectorConfig", "StopSignDetector"],
    "distance": ["CameraModel", "DepthDistance"],
    "lidar_segmentation": ["scan_points", "segment_scan"],
    "lidar_target": ["LidarTargetConfig", "LidarTargetState", "LidarTargetTracker"],
    "ekf": ["DistanceEKF", "EKFConfig"],
    "localisation": ["PoseFilter", "PoseFilterConfig", "wrap_angle"],
    "estimators": ["DistanceEstimator", "EKFEstimator", "RawDepthEstimator"],
    "obstacle_detector": ["ObstacleDetector", "ObstacleDetectorConfig"],
    "lane_follower": ["RouteFollower", "StanleyConfig", "StanleyController"],
    "perception": ["Perception", "PerceptionSample"],
    "size_distance": ["SizeDistance"],
    "speed": ["SpeedPI", "SpeedPIConfig", "SpeedProfile"],
})
