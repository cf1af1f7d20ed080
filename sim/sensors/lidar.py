"""RPLIDAR A2M12 2D LiDAR: a 360 deg scan cast with ``mujoco.mj_multiRay``.

Beam ``i`` points at angle ``2 pi i / n_beams`` counter-clockwise from the car's +x axis
in the scan plane (the body frame's x-y plane at the LiDAR's height). Ranges are metres;
a beam with no return inside [range_min, range_max] reads ``inf``. Noise: Gaussian with
std ``max(noise_floor_m, noise_rel * r)`` (the A2M12's ~1 % accuracy), and a dropout
probability per beam. The car's own geoms (group 3) are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from racf.sim._gl import ensure_gl_backend
from racf.sim.sensors.base import Sensor

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["LidarConfig", "Lidar2D"]

#: Geom groups the beams can hit (0, 1, 2: the map and its props); the car is group 3.
_VISIBLE_GROUPS = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)


@dataclass(frozen=True)
class LidarConfig:
    """2D LiDAR settings.

    Attributes:
        n_beams: beams per revolution (Quanser's driver resamples to 1 deg: 360).
        range_min_m, range_max_m: the A2M12's 0.15 to 12 m.
        noise_rel: range noise std as a share of range.
        noise_floor_m: smallest range noise std.
        dropout: probability that a beam returns nothing.
    """

    n_beams: int = 360
    range_min_m: float = 0.15
    range_max_m: float = 12.0
    noise_rel: float = 0.01
    noise_floor_m: float = 0.003
    dropout: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.n_beams, bool) or not isinstance(self.n_beams, (int, np.integer)):
            raise ValueError(f"n_beams must be an integer, got {self.n_beams!r}")
        if not 4 <= self.n_beams <= 4096:
            raise ValueError(f"n_beams must be in [4, 4096], got {self.n_beams}")
        if not 0.0 <= self.range_min_m < self.range_max_m <= 50.0:
            raise ValueError(f"need 0 <= range_min_m < range_max_m <= 50 m, got {self.range_min_m}, {self.range_max_m}")
        if not 0.0 <= self.noise_rel <= 0.2:
            raise ValueError(f"noise_rel must be in [0, 0.2], got {self.noise_rel}")
        if not 0.0 <= self.noise_floor_m <= 0.5:
            raise ValueError(f"noise_floor_m must be in [0, 0.5] m, got {self.noise_floor_m}")
        if not 0.0 <= self.dropout < 1.0:
            raise ValueError(f"dropout must be in [0, 1), got {self.dropout}")

    @property
    def angles(self) -> np.ndarray:
        """(n_beams,) beam angles in radians, CCW from the car's +x."""
        return np.arange(self.n_beams) * (2 * np.pi / self.n_beams)


class Lidar2D(Sensor):
    """Ranges of one scan: (n_beams,) float32 metres, ``inf`` = no return."""

    name = "lidar"
    dtype = np.float32
    low, high = 0.0, np.inf

    def __init__(self, config: LidarConfig, site: str = "lidar") -> None:
        self.config = config
        self.site = site
        self.shape = (config.n_beams,)
        angles = config.angles
        self._dirs_body = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
        self._geomid = np.zeros(config.n_beams, np.int32)
        self._dist = np.zeros(config.n_beams, np.float64)

    def true_ranges(self, model, data) -> np.ndarray:
        """(n_beams,) noise-free ranges in metres; -1 where a beam hits nothing."""
        site = data.site(self.site)
        vec = (self._dirs_body @ site.xmat.reshape(3, 3).T).ravel()
        mujoco.mj_multiRay(model, data, site.xpos.astype(np.float64), vec, _VISIBLE_GROUPS, 1, -1,
                           self._geomid, self._dist, None, self.config.n_beams, self.config.range_max_m * 2)
        return self._dist.copy()

    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        c = self.config
        r = self.true_ranges(model, data)
        hit = r >= 0
        sigma = np.maximum(c.noise_floor_m, c.noise_rel * np.abs(r))
        noisy = r + sigma * rng.standard_normal(r.shape)
        valid = hit & (noisy >= c.range_min_m) & (noisy <= c.range_max_m)
        if c.dropout > 0:
            valid &= rng.random(r.shape) >= c.dropout
        return np.where(valid, noisy, np.inf).astype(np.float32)
