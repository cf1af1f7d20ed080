"""One sensor reading <-> one ROS 2 message, in Quanser's conventions (:mod:`.topics`).

Each ``*_msg`` builds the message a QCar 2 node would publish for a reading of racf's
observation; each ``*_from`` reads one back into the observation's form. What a round trip
keeps: colour bit for bit; depth to the millimetre (mono16: within 0.5 mm, 0 = no return; bit for
bit for racf's depth camera, which quantises to the D435's 1 mm z16 unit);
the LiDAR's ranges bit for bit once snapped back to the A2M12's 1 mm resolution; the IMU, the
encoder and the fix bit for bit in float32 (checked in the tests over many values).
"""

from __future__ import annotations

import math

import numpy as np

from racf.experiments.bags.topics import typestore

__all__ = ["ns_of", "seconds_of", "header", "image_msg", "rgb_from", "depth_msg", "depth_from", "camera_info_msg",
           "scan_msg", "scan_from", "bins_msg", "bins_from", "imu_msg", "joint_msg", "pose_msg", "pose_from",
           "command_msg", "tf_msg", "float_msg", "array_msg", "mask_msg", "stamp_of", "empty_image"]

#: mono16 depth: millimetres per metre.
MM_PER_M = 1000.0


def ns_of(t_s: float) -> int:
    """A time in seconds as integer nanoseconds (a bag's clock)."""
    return int(round(t_s * 1e9))


def seconds_of(ns: int) -> float:
    return ns / 1e9


def _types():
    return typestore().types


def header(t_ns: int, frame: str):
    T = _types()
    return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=t_ns // 1_000_000_000,
                                                                           nanosec=t_ns % 1_000_000_000),
                                    frame_id=frame)


def stamp_of(msg) -> int:
    """A message's header stamp, ns."""
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


def _image(t_ns: int, frame: str, pixels: np.ndarray, encoding: str):
    pixels = np.ascontiguousarray(pixels)
    h, w = pixels.shape[:2]
    return _types()["sensor_msgs/msg/Image"](header=header(t_ns, frame), height=h, width=w, encoding=encoding,
                                             is_bigendian=0, step=pixels.strides[0],
                                             data=pixels.view(np.uint8).reshape(-1))


def empty_image(msg) -> bool:
    """Quanser's rgbd node publishes an empty, unstamped image when no new frame is ready."""
    return int(msg.width) == 0 or int(msg.height) == 0 or len(msg.data) == 0


def image_msg(rgb: np.ndarray, t_ns: int, frame: str = "color_image"):
    """An (H, W, 3) uint8 RGB frame as ``bgr8``."""
    return _image(t_ns, frame, np.asarray(rgb, np.uint8)[..., ::-1], "bgr8")


def rgb_from(msg) -> np.ndarray:
    """(H, W, 3) uint8 RGB from a ``bgr8``, ``rgb8``, ``bgra8`` or ``rgba8`` image."""
    channels = {"bgr8": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4}
    if msg.encoding not in channels:
        raise ValueError(f"a colour image's encoding must be one of {sorted(channels)}, got {msg.encoding!r}")
    rows = np.asarray(msg.data, np.uint8).reshape(msg.height, msg.step)
    px = rows[:, : msg.width * channels[msg.encoding]].reshape(msg.height, msg.width, channels[msg.encoding])[..., :3]
    return np.ascontiguousarray(px[..., ::-1] if msg.encoding.startswith("bgr") else px)


def depth_msg(depth_m: np.ndarray, t_ns: int, frame: str = "depth_image"):
    """An (H, W) float depth in metres (0 = no return) as ``mono16`` millimetres, rounded."""
    mm = np.clip(np.rint(np.asarray(depth_m, np.float64) * MM_PER_M), 0, 65535).astype("<u2")
    return _image(t_ns, frame, mm, "mono16")


def depth_from(msg) -> np.ndarray:
    """(H, W) float32 metres (0 = no return) from ``mono16``/``16UC1`` millimetres or ``32FC1`` metres."""
    if msg.encoding in ("mono16", "16UC1"):
        dtype = ">u2" if msg.is_bigendian else "<u2"
        rows = np.asarray(msg.data, np.uint8).reshape(msg.height, msg.step)[:, : msg.width * 2]
        mm = np.ascontiguousarray(rows).view(dtype).reshape(msg.height, msg.width)
        # The D435's z16 unit times the count, in float32: the form racf's depth camera quantises to.
        return mm.astype(np.float32) * np.float32(1.0 / MM_PER_M)
    if msg.encoding == "32FC1":
        dtype = ">f4" if msg.is_bigendian else "<f4"
        rows = np.asarray(msg.data, np.uint8).reshape(msg.height, msg.step)[:, : msg.width * 4]
        metres = np.ascontiguousarray(rows).view(dtype).reshape(msg.height, msg.width).astype(np.float32)
        return np.where(np.isfinite(metres), metres, 0.0).astype(np.float32)
    raise ValueError(f"a depth image's encoding must be mono16, 16UC1 or 32FC1, got {msg.encoding!r}")


def camera_info_msg(width: int, height: int, fx: float, fy: float, cx: float, cy: float, t_ns: int,
                    frame: str = "color_image"):
    """A pinhole ``CameraInfo`` with no distortion (racf's model of the D435)."""
    k = np.array([fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0])
    p = np.array([fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0])
    T = _types()
    roi = T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    return T["sensor_msgs/msg/CameraInfo"](header=header(t_ns, frame), height=height, width=width,
                                           distortion_model="plumb_bob", d=np.zeros(5), k=k,
                                           r=np.eye(3).reshape(-1), p=p, binning_x=0, binning_y=0, roi=roi)


def scan_msg(ranges: np.ndarray, t_ns: int, rev_hz: float, range_max_m: float, frame: str = "base_scan"):
    """One revolution in scan order (sample i at i * 360 / N deg clockwise, 0 = no return, NaN = not
    read) as Quanser's ``lidar.cpp`` lays it out: ranges reversed, ``angle_min``/``angle_max`` the
    first and last sample's heading, ``angle_increment = angle_max / N``."""
    ranges = np.asarray(ranges, np.float64)
    n = ranges.size
    last = (n - 1) * 2 * math.pi / n
    return _types()["sensor_msgs/msg/LaserScan"](
        header=header(t_ns, frame), angle_min=0.0, angle_max=last, angle_increment=last / n,
        time_increment=(1.0 / rev_hz) / n, scan_time=1.0 / rev_hz, range_min=0.0, range_max=float(range_max_m),
        ranges=ranges[::-1].astype(np.float32), intensities=np.zeros(0, np.float32))


def scan_from(msg, quantum_m: float = 0.001) -> np.ndarray:
    """(N,) float64 ranges in scan order from a Quanser ``/scan``: the reverse undone, snapped to the
    range resolution ``quantum_m`` (0: as stored), no return (0, inf) as 0, NaN kept."""
    ranges = np.asarray(msg.ranges, np.float32)[::-1].astype(np.float64)
    ranges[np.isinf(ranges)] = 0.0
    if quantum_m > 0:
        ranges = np.round(ranges / quantum_m) * quantum_m
    return ranges


def bins_msg(bins: np.ndarray, t_ns: int, frame: str = "base_link"):
    """Car-frame one-degree bins (bin j at j deg counter-clockwise from forward, inf = no return) as a
    standard ``LaserScan``."""
    bins = np.asarray(bins, np.float32)
    n = bins.size
    return _types()["sensor_msgs/msg/LaserScan"](
        header=header(t_ns, frame), angle_min=0.0, angle_max=2 * math.pi * (n - 1) / n,
        angle_increment=2 * math.pi / n, time_increment=0.0, scan_time=0.0, range_min=0.0,
        range_max=float("inf"), ranges=bins.copy(), intensities=np.zeros(0, np.float32))


def bins_from(msg) -> np.ndarray:
    return np.asarray(msg.ranges, np.float32).copy()


def imu_msg(yaw_rate: float, accel_x: float, t_ns: int, frame: str = "base_link"):
    """The hardware node's IMU: gyro z and accelerometer x filled, orientation at identity."""
    T = _types()
    vec = T["geometry_msgs/msg/Vector3"]
    return T["sensor_msgs/msg/Imu"](header=header(t_ns, frame),
                                    orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                                    orientation_covariance=np.zeros(9), angular_velocity=vec(x=0.0, y=0.0, z=float(yaw_rate)),
                                    angular_velocity_covariance=np.zeros(9),
                                    linear_acceleration=vec(x=float(accel_x), y=0.0, z=0.0),
                                    linear_acceleration_covariance=np.zeros(9))


def joint_msg(counts: float, counts_per_s: float, t_ns: int, frame: str = "base_link"):
    """The hardware node's ``JointState``: no names; the motor encoder's counts and counts/s, no current."""
    return _types()["sensor_msgs/msg/JointState"](header=header(t_ns, frame), name=[],
                                                  position=np.array([counts], np.float64),
                                                  velocity=np.array([counts_per_s], np.float64),
                                                  effort=np.array([math.nan]))


def pose_msg(x: float, y: float, yaw: float, t_ns: int, frame: str = "map"):
    T = _types()
    yaw = float(yaw)
    return T["geometry_msgs/msg/PoseStamped"](
        header=header(t_ns, frame),
        pose=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0),
                                         orientation=T["geometry_msgs/msg/Quaternion"](
                                             x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))))


def pose_from(msg) -> np.ndarray:
    """(x, y, yaw) float32 from a ``PoseStamped`` (yaw from its quaternion)."""
    q = msg.pose.orientation
    if q.x == 0.0 and q.y == 0.0:
        # A pure yaw: 2 atan2(z, w) gives back any yaw in (-2 pi, 2 pi) as it was written, unwrapped.
        yaw = 2.0 * math.atan2(q.z, q.w)
    else:
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    return np.array([msg.pose.position.x, msg.pose.position.y, yaw], np.float32)


def command_msg(steering_rad: float, throttle_mps: float):
    """Quanser's ``MotorCommands``: values by position, steering first."""
    return _types()["qcar2_interfaces/msg/MotorCommands"](motor_names=["steering_angle", "motor_throttle"],
                                                          values=np.array([steering_rad, throttle_mps], np.float64))


def tf_msg(transforms: list[tuple[str, str, tuple[float, float, float], float]], t_ns: int):
    """``TFMessage`` of (parent, child, (x, y, z), yaw) transforms."""
    T = _types()
    out = []
    for parent, child, (x, y, z), yaw in transforms:
        out.append(T["geometry_msgs/msg/TransformStamped"](
            header=header(t_ns, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z)),
                rotation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)))))
    return T["tf2_msgs/msg/TFMessage"](transforms=out)


def float_msg(value: float):
    return _types()["std_msgs/msg/Float64"](data=float(value))


def array_msg(values: np.ndarray):
    T = _types()
    layout = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
    return T["std_msgs/msg/Float64MultiArray"](layout=layout, data=np.asarray(values, np.float64))


def mask_msg(mask: np.ndarray, t_ns: int, frame: str = "color_image"):
    """A boolean mask as ``mono8`` (255 = set)."""
    return _image(t_ns, frame, np.where(np.asarray(mask, bool), 255, 0).astype(np.uint8), "mono8")


def mask_from(msg) -> np.ndarray:
    rows = np.asarray(msg.data, np.uint8).reshape(msg.height, msg.step)[:, : msg.width]
    return rows > 0
