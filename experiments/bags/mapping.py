"""The mapping file: how another recording's topics, camera and LiDAR meet racf's car.

A TOML file with up to four tables, every key optional::

    [topics]            # stream -> topic name (defaults: Quanser's, racf's /pose_estimate)
    rgb = "/qcar2/camera/color_image"
    depth = "/qcar2/camera/depth_image"
    scan = "/qcar2/scan"
    imu = "/qcar2/qcar2_imu"
    joint = "/qcar2/qcar2_joint"
    fix = "/qcar2/pose_estimate"

    [camera]
    crop = [0, 0, 1280, 720]   # x0, y0, x1, y1 of the frame to keep, pixels (before resizing)
    size = [320, 240]          # resize to (width, height): the car's camera model at that size
    intrinsics = [924.0, 924.0, 640.0, 360.0]   # fx, fy, cx, cy of the recorded frames (CameraInfo's K),
                               # pixels; or hfov_deg = 69.4 (square pixels, centred): the car's perception
                               # then uses these, cropped and resized with the frames (default: racf's D435)

    [lidar]
    yaw_deg = 180.0            # base_scan's forward in base_link (Quanser's car: 180; its virtual car: 0)
    position_m = [-0.012, 0.0] # base_scan's origin in base_link, x forward, y left (default: racf's model)
    driver = "quanser"         # "quanser": Quanser's read of 384 and its 1-degree filter; "none": the scan is the bins
    quantum_m = 0.001          # snap ranges to the A2M12's 1 mm resolution (0: as stored; default: 1 mm
                               # through Quanser's driver, as stored with driver = "none")
    read_per_rev = 384

    [mission]                  # for a bag racf did not write: the episode's spec fields (racf trials' names)
    sign = 2
    speed = 1.0
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

from racf.errors import UserError
from racf.experiments.bags.topics import QUANSER_TOPICS, RACF_TOPICS

__all__ = ["Mapping", "DEFAULT_TOPICS", "LIDAR_DRIVERS"]

#: The stream each topic feeds, and its topic in a bag racf wrote (Quanser's names).
DEFAULT_TOPICS = {**{k: QUANSER_TOPICS[k].name for k in ("rgb", "depth", "scan", "imu", "joint")},
                  "fix": RACF_TOPICS["fix"].name}
LIDAR_DRIVERS = ("quanser", "none")
_TABLES = {"topics": tuple(DEFAULT_TOPICS), "camera": ("crop", "size", "intrinsics", "hfov_deg"),
           "lidar": ("yaw_deg", "position_m", "driver", "quantum_m", "read_per_rev"), "mission": None}


@dataclass(frozen=True)
class Mapping:
    """How a recording's streams reach the car (see the module docstring; defaults: a bag racf wrote).

    ``lidar_driver`` None: from the bag's spec (``ideal`` profile: ``none``), else ``quanser``.
    """

    topics: dict = field(default_factory=lambda: dict(DEFAULT_TOPICS))
    camera_crop: tuple[int, int, int, int] | None = None
    camera_size: tuple[int, int] | None = None
    #: The recorded frames' pinhole intrinsics (fx, fy, cx, cy, pixels), or their horizontal field of
    #: view (square pixels, the principal point at the centre); None: racf's D435 model.
    camera_intrinsics: tuple[float, float, float, float] | None = None
    camera_hfov_deg: float | None = None
    lidar_yaw_deg: float = 180.0
    lidar_position_m: tuple[float, float] | None = None
    lidar_driver: str | None = None
    lidar_quantum_m: float | None = None
    read_per_rev: int = 384
    mission: dict = field(default_factory=dict)
    source: str = "(defaults)"

    @classmethod
    def load(cls, path: str | Path | None) -> "Mapping":
        """The mapping in ``path`` (None: the defaults); UserError names a wrong key or value."""
        if path is None:
            return cls()
        path = Path(path)
        try:
            raw = tomllib.loads(path.read_text())
        except FileNotFoundError:
            raise UserError(f"mapping file {path} does not exist") from None
        except tomllib.TOMLDecodeError as err:
            raise UserError(f"mapping file {path} is not valid TOML: {err}") from None
        return cls.from_dict(raw, str(path))

    @classmethod
    def from_dict(cls, raw: dict, source: str = "(mapping)") -> "Mapping":
        def bad(what: str) -> UserError:
            return UserError(f"mapping {source}: {what}")

        unknown = sorted(set(raw) - set(_TABLES))
        if unknown:
            raise bad(f"no table {unknown[0]!r}; the tables are {', '.join(f'[{t}]' for t in _TABLES)}")
        for table, keys in _TABLES.items():
            if table in raw and not isinstance(raw[table], dict):
                raise bad(f"[{table}] must be a table")
            extra = sorted(set(raw.get(table, {})) - set(keys)) if keys is not None else []
            if extra:
                raise bad(f"[{table}] has no key {extra[0]!r}; it takes {', '.join(keys)}")
        out = cls(source=source)
        topics = dict(DEFAULT_TOPICS)
        for key, value in raw.get("topics", {}).items():
            if not (isinstance(value, str) and value.startswith("/")):
                raise bad(f"[topics] {key} must be a topic name starting with '/', got {value!r}")
            topics[key] = value
        camera = raw.get("camera", {})
        crop = camera.get("crop")
        if crop is not None and not (isinstance(crop, list) and len(crop) == 4 and all(isinstance(v, int) for v in crop)
                                     and 0 <= crop[0] < crop[2] and 0 <= crop[1] < crop[3]):
            raise bad(f"[camera] crop must be [x0, y0, x1, y1] whole pixels with x0 < x1, y0 < y1, got {crop!r}")
        size = camera.get("size")
        if size is not None and not (isinstance(size, list) and len(size) == 2
                                     and all(isinstance(v, int) and 16 <= v <= 4096 for v in size)):
            raise bad(f"[camera] size must be [width, height], whole pixels in [16, 4096], got {size!r}")
        intrinsics, hfov = camera.get("intrinsics"), camera.get("hfov_deg")
        if intrinsics is not None and hfov is not None:
            raise bad("[camera] takes intrinsics or hfov_deg, not both (intrinsics say more: keep those)")
        if intrinsics is not None and not (isinstance(intrinsics, list) and len(intrinsics) == 4
                                           and all(_number(v) for v in intrinsics)
                                           and intrinsics[0] > 0 and intrinsics[1] > 0):
            raise bad(f"[camera] intrinsics must be [fx, fy, cx, cy] in pixels with fx, fy > 0 (CameraInfo's K: "
                      f"K[0], K[4], K[2], K[5]), got {intrinsics!r}")
        if hfov is not None and not (_number(hfov) and 1.0 <= hfov <= 179.0):
            raise bad(f"[camera] hfov_deg must be a number of degrees in [1, 179], got {hfov!r}")
        lidar = raw.get("lidar", {})
        position = lidar.get("position_m")
        if position is not None and not (isinstance(position, list) and len(position) == 2
                                         and all(_number(v) and abs(v) <= 1.0 for v in position)):
            raise bad(f"[lidar] position_m must be [x, y] in metres on the body (x forward, y left), each within "
                      f"1 m, got {position!r}")
        yaw = lidar.get("yaw_deg", out.lidar_yaw_deg)
        if not (isinstance(yaw, (int, float)) and not isinstance(yaw, bool) and math.isfinite(yaw)
                and float(yaw) % 1.0 == 0.0):
            raise bad(f"[lidar] yaw_deg must be whole degrees (a multiple of the 1-degree bins), got {yaw!r}")
        driver = lidar.get("driver")
        if driver is not None and driver not in LIDAR_DRIVERS:
            raise bad(f"[lidar] driver must be one of {', '.join(LIDAR_DRIVERS)}, got {driver!r}")
        quantum = lidar.get("quantum_m")
        if quantum is not None and not (isinstance(quantum, (int, float)) and not isinstance(quantum, bool)
                                        and 0.0 <= quantum <= 0.1):
            raise bad(f"[lidar] quantum_m must be a number of metres in [0, 0.1], got {quantum!r}")
        read = lidar.get("read_per_rev", out.read_per_rev)
        if not (isinstance(read, int) and not isinstance(read, bool) and 1 <= read <= 100_000):
            raise bad(f"[lidar] read_per_rev must be a whole number in [1, 100000], got {read!r}")
        return replace(out, topics=topics, camera_crop=tuple(crop) if crop else None,
                       camera_size=tuple(size) if size else None,
                       camera_intrinsics=tuple(map(float, intrinsics)) if intrinsics else None,
                       camera_hfov_deg=None if hfov is None else float(hfov), lidar_yaw_deg=float(yaw),
                       lidar_position_m=tuple(map(float, position)) if position else None, lidar_driver=driver,
                       lidar_quantum_m=None if quantum is None else float(quantum), read_per_rev=read, mission=dict(raw.get("mission", {})))

    def car_intrinsics(self, frame_w: int, frame_h: int, size: tuple[int, int]) -> tuple[float, float, float, float] | None:
        """The intrinsics (fx, fy, cx, cy) of the frames the car gets, from the declared ones of the
        recorded ``frame_w`` x ``frame_h`` frames, cropped and resized as the car's frames are (OpenCV's
        pixel centres: a resize by s maps column u to (u + 0.5) / s - 0.5). None: none declared."""
        if self.camera_intrinsics is not None:
            fx, fy, cx, cy = self.camera_intrinsics
        elif self.camera_hfov_deg is not None:
            fx = fy = (frame_w / 2.0) / math.tan(math.radians(self.camera_hfov_deg) / 2.0)
            cx, cy = (frame_w - 1) / 2.0, (frame_h - 1) / 2.0
        else:
            return None
        x0, y0, x1, y1 = self.camera_crop if self.camera_crop is not None else (0, 0, frame_w, frame_h)
        sx, sy = (x1 - x0) / size[0], (y1 - y0) / size[1]
        return fx / sx, fy / sy, (cx - x0 + 0.5) / sx - 0.5, (cy - y0 + 0.5) / sy - 0.5


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
