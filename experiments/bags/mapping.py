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

    [lidar]
    yaw_deg = 180.0            # base_scan's forward in base_link (Quanser's car: 180; its virtual car: 0)
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
_TABLES = {"topics": tuple(DEFAULT_TOPICS), "camera": ("crop", "size"),
           "lidar": ("yaw_deg", "driver", "quantum_m", "read_per_rev"), "mission": None}


@dataclass(frozen=True)
class Mapping:
    """How a recording's streams reach the car (see the module docstring; defaults: a bag racf wrote).

    ``lidar_driver`` None: from the bag's spec (``ideal`` profile: ``none``), else ``quanser``.
    """

    topics: dict = field(default_factory=lambda: dict(DEFAULT_TOPICS))
    camera_crop: tuple[int, int, int, int] | None = None
    camera_size: tuple[int, int] | None = None
    lidar_yaw_deg: float = 180.0
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
        lidar = raw.get("lidar", {})
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
                       camera_size=tuple(size) if size else None, lidar_yaw_deg=float(yaw), lidar_driver=driver,
                       lidar_quantum_m=None if quantum is None else float(quantum), read_per_rev=read, mission=dict(raw.get("mission", {})))
