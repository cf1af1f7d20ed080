"""The localisation fix: the pose Quanser's LiDAR scan-matching localiser sends (``qcar2LidarToGPS``).

The physical car matches each LiDAR scan against a reference scan on a ~3.3 cm grid and
adds a drift on purpose. Per axis the drift is a sine (30 s period) whose amplitude is
|band-limited white noise| (Simulink semantics: held for ``drift_sample_s``, variance
``power / sample time``), rate-limited, then saturated at +-0.07/sqrt(2) m (so the drift
vector stays within 7 cm). x and y draw their own noise; y's drift is the same construction
delayed by 45 to 75 fix samples. On top sits white noise for the grid quantisation.

The drift is a pure function of time after ``reset``: reading out of order, or twice, gives
the same offset.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from racf.sim.sensors.base import Sensor, check_range
from racf.sim.vehicle.qcar2 import QCar2

__all__ = ["LocaliserConfig", "LocalisationFix", "LOCALISATIONS"]

#: Where the ``gps`` observation comes from: ``qcar2``, fixes shaped like Quanser's LiDAR
#: scan-matching localiser (drift and noise, one per LiDAR scan); ``true``, the true pose at
#: every step (for ablations). The env's ``localisation`` setting takes one of them.
LOCALISATIONS = ("qcar2", "true")


@dataclass(frozen=True)
class LocaliserConfig:
    """Drift and noise of the localisation fix (SI units).

    Attributes:
        drift_period_s: period of the drift's sine.
        drift_noise_power: power of the band-limited white noise behind the amplitude, m^2 s
            (the held value's variance is ``power / drift_sample_s``).
        drift_sample_s: how long each noise value is held.
        drift_rate_limit: the fastest the amplitude may change, m/s.
        drift_max_m: saturation of the amplitude (so of each axis's drift), m.
        y_delay_samples: (low, high) inclusive range of the per-episode delay of y's drift,
            in fix samples.
        noise_xy_m: white position noise std per axis; the scan-match grid is 3.3 cm and a
            uniform error on it has std 3.3 / sqrt(12) = 0.95 cm.
        noise_yaw_rad: white heading noise std.
    """

    drift_period_s: float = 30.0
    drift_noise_power: float = 0.002
    drift_sample_s: float = 5.0
    drift_rate_limit: float = 0.1
    drift_max_m: float = 0.07 / math.sqrt(2)
    y_delay_samples: tuple[int, int] = (45, 75)
    noise_xy_m: float = 0.01
    noise_yaw_rad: float = 0.01

    def __post_init__(self) -> None:
        check_range("drift_period_s", self.drift_period_s, 0.0, 3600.0, low_open=True)
        check_range("drift_noise_power", self.drift_noise_power, 0.0, 1.0)
        check_range("drift_sample_s", self.drift_sample_s, 0.0, 3600.0, low_open=True)
        check_range("drift_rate_limit", self.drift_rate_limit, 0.0, 10.0, low_open=True)
        check_range("drift_max_m", self.drift_max_m, 0.0, 1.0)
        check_range("noise_xy_m", self.noise_xy_m, 0.0, 1.0)
        check_range("noise_yaw_rad", self.noise_yaw_rad, 0.0, math.pi)
        delay = self.y_delay_samples
        if (not isinstance(delay, tuple) or len(delay) != 2
                or not all(isinstance(n, numbers.Integral) and not isinstance(n, bool) for n in delay)
                or not 0 <= delay[0] <= delay[1] <= 10_000):
            raise ValueError(f"y_delay_samples must be a tuple (low, high) of ints with 0 <= low <= high <= 10000, "
                             f"got {delay!r}")


class _Amplitude:
    """One axis's drift amplitude: saturate(rate_limit(|held Gaussian noise|)), a pure function of t.

    The held values start at sample index ``k0`` (before any time the fix is evaluated at,
    negative times included) and are drawn in blocks, each from its own seed sequence, so
    they are the same whatever order times are asked in. Before ``k0`` the first value holds.
    """

    _BLOCK = 64

    def __init__(self, config: LocaliserConfig, entropy: int, axis: int, t_start: float) -> None:
        self._entropy, self._axis = entropy, axis
        self._ts = config.drift_sample_s
        self._std = math.sqrt(config.drift_noise_power / config.drift_sample_s)
        self._rate = config.drift_rate_limit
        self._max = config.drift_max_m
        self._k0 = math.floor(t_start / self._ts)
        self._targets: list[float] = []  # |noise| held from sample k0 + i on
        self._starts: list[float] = []  # the rate-limited amplitude when sample k0 + i begins

    def _extend(self, n: int) -> None:
        step = self._rate * self._ts
        while len(self._targets) < n:
            seq = np.random.SeedSequence(self._entropy, spawn_key=(self._axis, len(self._targets) // self._BLOCK))
            for v in np.abs(np.random.default_rng(seq).standard_normal(self._BLOCK)) * self._std:
                if self._starts:
                    r, target = self._starts[-1], self._targets[-1]
                    self._starts.append(r + min(max(target - r, -step), step))
                else:
                    self._starts.append(float(v))  # start settled on the first target
                self._targets.append(float(v))

    def __call__(self, t: float) -> float:
        k = math.floor(t / self._ts)
        i = k - self._k0
        if i < 0:
            self._extend(1)
            return min(self._starts[0], self._max)
        self._extend(i + 1)
        r, target = self._starts[i], self._targets[i]
        reach = self._rate * min(max(t - k * self._ts, 0.0), self._ts)
        return min(r + min(max(target - r, -reach), reach), self._max)


class LocalisationFix(Sensor):
    """(x, y, yaw) float32 in the map frame (m, m, rad): the true pose + drift + white noise.

    Args:
        car: the car whose pose is measured.
        config: drift and noise; default ``LocaliserConfig()``.
        fix_period_s: time between two fixes (the unit of ``y_delay_samples``).
        exact: True gives the true pose, with no drift, no noise and no draws.

    ``reset(rng)`` draws the episode's drift (noise sequences, y's delay, the sine's phase);
    a ``read`` before any ``reset`` resets from its own generator first.
    """

    name = "gps"
    shape = (3,)
    dtype = np.float32
    low, high = -np.inf, np.inf

    def __init__(self, car: QCar2, config: LocaliserConfig | None = None, fix_period_s: float = 0.1,
                 exact: bool = False) -> None:
        check_range("fix_period_s", fix_period_s, 0.0, 10.0, low_open=True)
        self.car = car
        self.config = config or LocaliserConfig()
        self.fix_period_s = float(fix_period_s)
        self.exact = bool(exact)
        self._axes: tuple[_Amplitude, _Amplitude] | None = None
        self._y_delay_s = 0.0
        self._phase = 0.0

    def reset(self, rng: np.random.Generator) -> None:
        """Draws the episode's noise sequences, y's delay and a sine phase (exact: draws nothing)."""
        if self.exact:
            self._axes = None
            return
        cfg = self.config
        entropy = int(rng.integers(2**63))
        low, high = cfg.y_delay_samples
        self._y_delay_s = int(rng.integers(low, high + 1)) * self.fix_period_s
        self._phase = float(rng.uniform(-math.pi, math.pi))  # episodes don't all start at zero drift
        t_start = -(high * self.fix_period_s + cfg.drift_sample_s)  # covers y's delayed times from t = 0
        self._axes = (_Amplitude(cfg, entropy, 0, t_start), _Amplitude(cfg, entropy, 1, t_start))

    def drift(self, t: float) -> np.ndarray:
        """(2,) the (dx, dy) drift at time ``t``, m; deterministic given the reset draws."""
        if self.exact:
            return np.zeros(2)
        if self._axes is None:
            raise RuntimeError("LocalisationFix.drift needs reset(rng) first")
        omega = 2.0 * math.pi / self.config.drift_period_s
        ty = t - self._y_delay_s
        return np.array([self._axes[0](t) * math.sin(omega * t + self._phase),
                         self._axes[1](ty) * math.sin(omega * ty + self._phase)])

    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        s = self.car.state(data)
        if self.exact:
            return np.array([s.x, s.y, _wrap(s.yaw)], np.float32)
        if self._axes is None:
            self.reset(rng)
        dx, dy = self.drift(float(data.time))
        cfg = self.config
        noise = rng.normal(0.0, 1.0, 3) * (cfg.noise_xy_m, cfg.noise_xy_m, cfg.noise_yaw_rad)
        return np.array([s.x + dx + noise[0], s.y + dy + noise[1], _wrap(s.yaw + noise[2])], np.float32)


def _wrap(angle: float) -> float:
    """The angle in (-pi, pi]."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)
