"""The topics of a QCar 2 recording: Quanser's names, types, frames and conventions, and racf's own.

Read from Quanser's ROS 2 nodes (``quanser/Quanser_Academic_Resources``,
``5_research/sdcs/qcar2/ros2/src/qcar2_nodes/src``, commit d1e5b29 of 2025-06-13):

- ``rgbd.cpp``: ``camera/color_image`` (``bgr8``, frame ``color_image``) and
  ``camera/depth_image`` (``mono16``, frame ``depth_image``; the RealSense's millimetres), 30 Hz;
  1280 x 720 on the car, 640 x 480 in the virtual launch. With no new frame it publishes an
  empty image with no stamp: a reader drops those. It publishes no ``CameraInfo``.
- ``lidar.cpp``: ``/scan`` (``LaserScan``, frame ``base_scan``): ``angle_min`` and
  ``angle_max`` the first and last sample's heading, ``angle_increment = angle_max / N``,
  ``time_increment = (1 / rate) / N``, ranges filled in reverse scan order "for the CCW
  convention", no intensities, no return = 0.
- ``qcar2_hardware.cpp``: ``qcar2_imu`` (``Imu``, frame ``base_link``, gyro and accelerometer,
  orientation left at identity), ``qcar2_joint`` (``JointState``, no names: position = the
  motor encoder's counts, velocity = counts/s, effort = motor current), and it takes
  ``qcar2_motor_speed_cmd`` (``qcar2_interfaces/msg/MotorCommands``: ``values`` read by
  position, ``[steering_angle rad, motor_throttle m/s]``).
- ``fixed_lidar_frame.cpp``: ``base_link`` -> ``base_scan`` at (0.1, 0, 0), yaw 3.14.

racf adds what a viewer needs and Quanser's nodes leave out: ``/camera/camera_info`` (the
calibration), ``/tf_static`` (the mounts of racf's model), ``/tf`` (``map`` -> ``base_link``
from the car's own pose estimate), the localiser's fix on ``/pose_estimate`` (the name the
community's ``ekf_fusor`` reads its correction from; Quanser's repository has no such node),
and its own signals under ``/racf/``: ``/racf/car/<column>`` (what the car's software made:
the defence's distance ``d_fused``, its gate ``w``, ``flag``, the brake, ...),
``/racf/attack_active``, and ``/racf/ground_truth/<column>`` (the referee's, which the car
never sees).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

__all__ = ["Topic", "QUANSER_TOPICS", "RACF_TOPICS", "REQUIRED", "MOTOR_COMMANDS_MSG", "typestore",
           "CAR_PREFIX", "TRUTH_PREFIX", "SCAN_TIMES", "SCAN_DELIVERED", "SIGN_MASK", "SPEC_KEY"]


@dataclass(frozen=True)
class Topic:
    """One topic of a recording.

    Attributes:
        name: the topic (Quanser's nodes run in the root namespace).
        msgtype: its ROS 2 message type.
        frame: the ``header.frame_id`` (empty: the message has no header).
        rate: how often it is published, in words.
        what: what it carries, with units and conventions.
    """

    name: str
    msgtype: str
    frame: str
    rate: str
    what: str


#: The car's sensors and command as Quanser's nodes publish them. The key names the stream.
QUANSER_TOPICS: dict[str, Topic] = {
    "rgb": Topic("/camera/color_image", "sensor_msgs/msg/Image", "color_image", "30 Hz",
                 "colour frame, bgr8 (the RealSense D435's, rgbd.cpp)"),
    "depth": Topic("/camera/depth_image", "sensor_msgs/msg/Image", "depth_image", "30 Hz",
                   "depth frame aligned to the colour one, mono16 millimetres, 0 = no return"),
    "scan": Topic("/scan", "sensor_msgs/msg/LaserScan", "base_scan", "10 Hz (one per revolution)",
                  "the A2M12's revolution in Quanser's layout: ranges in reverse scan order, "
                  "angle_increment = angle_max / N, 0 = no return (NaN: a sample the driver's read skips)"),
    "imu": Topic("/qcar2_imu", "sensor_msgs/msg/Imu", "base_link", "50 Hz",
                 "gyro rad/s and accelerometer m/s^2 (racf models z rate and x acceleration); orientation identity"),
    "joint": Topic("/qcar2_joint", "sensor_msgs/msg/JointState", "base_link", "50 Hz",
                   "motor encoder: position counts, velocity counts/s, effort NaN (racf models no current)"),
    "command": Topic("/qcar2_motor_speed_cmd", "qcar2_interfaces/msg/MotorCommands", "", "50 Hz",
                     "motor_names [steering_angle, motor_throttle], values [rad, m/s]"),
}

#: racf's additions: what a viewer needs, and racf's own signals.
RACF_TOPICS: dict[str, Topic] = {
    "camera_info": Topic("/camera/camera_info", "sensor_msgs/msg/CameraInfo", "color_image", "with each frame",
                         "the colour camera's pinhole calibration (racf's model of the D435)"),
    "fix": Topic("/pose_estimate", "geometry_msgs/msg/PoseStamped", "map", "10 Hz (one per scan)",
                 "the localiser's fix (Quanser's LiDAR scan matching, qcar2LidarToGPS), map frame"),
    "tf": Topic("/tf", "tf2_msgs/msg/TFMessage", "", "50 Hz", "map -> base_link, the car's own pose estimate"),
    "tf_static": Topic("/tf_static", "tf2_msgs/msg/TFMessage", "", "once",
                       "base_link -> base_scan (yaw 180 deg), color_image, depth_image: the mounts of racf's model"),
    "scan_times": Topic("/racf/scan/sample_times", "std_msgs/msg/Float64MultiArray", "", "with each scan",
                        "when each sample of /scan was taken, s (racf's A2M12 casts by physics step; a "
                        "constant time_increment cannot say so)"),
    "scan_delivered": Topic("/racf/scan/delivered", "sensor_msgs/msg/LaserScan", "base_link", "where an attack acted",
                            "the 360 one-degree bins the car's software got, where an attack changed them after "
                            "the driver (CCW from the car's forward, inf = no return)"),
    "sign_mask": Topic("/racf/ground_truth/sign_mask", "sensor_msgs/msg/Image", "color_image", "with each frame",
                       "ground truth: the target's pixels in the frame (mono8, 255 = target)"),
    "car": Topic("/racf/car/<column>", "std_msgs/msg/Float64", "", "50 Hz",
                 "each numeric car-side column of the step log (d_fused: the defence's distance, w: its gate, "
                 "flag, brake, detected, ...)"),
    "attack_active": Topic("/racf/attack_active", "std_msgs/msg/Float64", "", "50 Hz",
                           "1.0 where an attack acted on the step's observation"),
    "truth": Topic("/racf/ground_truth/<column>", "std_msgs/msg/Float64", "", "50 Hz",
                   "each numeric referee column (d_true, x, y, yaw, speed, dist_to_stop_line, ...): ground truth, "
                   "never seen by the car"),
}

#: What a replay cannot run without (by stream key).
REQUIRED = ("rgb", "depth", "scan", "imu", "joint", "fix")
CAR_PREFIX, TRUTH_PREFIX = "/racf/car/", "/racf/ground_truth/"
SCAN_TIMES, SCAN_DELIVERED, SIGN_MASK = (RACF_TOPICS[k].name for k in ("scan_times", "scan_delivered", "sign_mask"))
#: The bag's custom-data key holding the episode's spec (JSON), which names its mission and build.
SPEC_KEY = "racf.spec"

#: ``qcar2_interfaces/msg/MotorCommands``, as Quanser's ``qcar2_interfaces`` declares it.
MOTOR_COMMANDS_MSG = """\
## Driving command for QCar2 to directly control the Steering angle and Motor throttle
#std_msgs/Header header

# Names of whether to drive steering or throttle. Must be "steering_angle" or "motor_throttle"
string[] motor_names

# Values for the "command_names".
# The order must be identical to the "command_names".
# Units are:
#   "rad" for "steering_angle"
#   "m/s" for "motor_throttle"
float64[] values
"""


@lru_cache(maxsize=1)
def typestore():
    """ROS 2 Humble's message types (rosbags) with Quanser's ``MotorCommands`` registered."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(MOTOR_COMMANDS_MSG, "qcar2_interfaces/msg/MotorCommands"))
    return store
