"""Car-side pose filter: odometry and the gyro between fixes, the localiser's fixes to stay anchored.

The QCar 2's localiser (scan matching on the real car, QLabs' pose server in simulation)
sends (x, y, yaw) at about 10 Hz with a slow drift on purpose; the encoder and the gyro
come at the control rate. Like Quanser's ``QCarEKF`` this filter fuses them, and it also
estimates the gyro's zero-rate offset, which would otherwise turn into heading drift
(0.5 deg/s is 30 deg a minute) whenever fixes are missing.

State ``s = [x, y, yaw, b]``: the body origin in the map frame (m), the heading (rad,
kept in (-pi, pi]) and the gyro bias b (rad/s). Prediction over dt with the encoder
speed v and the gyro rate w, on the unicycle model (midpoint heading):

    yaw <- yaw + (w - b) dt,   x <- x + v dt cos(yaw_mid),   y <- y + v dt sin(yaw_mid)

A fix z = (x, y, yaw) + noise measures the first three states (H = [I3 0]); the heading
innovation is wrapped, so crossing yaw = +-pi is harmless. The covariance update is the
Joseph form, symmetrised, so P stays symmetric PSD whatever the inputs.

Noises are continuous-time densities (per sqrt(Hz), i.e. the std of the error averaged
over one second), so the filter behaves the same at any control rate. Pure numpy.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["PoseFilterConfig", "PoseFilter", "wrap_angle"]


def wrap_angle(angle: float) -> float:
    """``angle`` wrapped to (-pi, pi]."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)


@dataclass(frozen=True)
class PoseFilterConfig:
    """Noise model of the pose filter, SI units.

    The localiser's fix is the true pose plus a slow drift (per axis a 30 s sine of
    amplitude up to about 5 cm: rms about 3.5 cm) plus about 1 cm of white noise, heading
    noise about 0.01 rad. The drift is too slow for odometry to tell from motion, so no
    filter removes it; the fix noise is set to the fix's whole error budget (drift rms and
    white noise, about 3-4 cm) so the filter averages the white noise over a few fixes
    instead of chasing it, and odometry (good to a few mm over 0.1 s) carries the pose
    between fixes. Quanser's ``QCarEKF`` assumes 0.1 m and 0.03 rad, looser still.

    Attributes:
        fix_std_m: std of a fix's x and y, m. Default 0.03: the drift's rms plus the white
            noise, about 3-4 cm.
        fix_std_yaw_rad: std of a fix's heading, rad. Default 0.02: twice the ~0.01 rad
            white noise, for scan-match heading errors at the map's symmetric spots.
        speed_std_mps: white-noise density of the encoder speed, m/s/sqrt(Hz). Quantisation
            is negligible (6.9 um a count, and counts telescope into distance); the term
            stands for wheel slip and tyre-radius error, a few % of 1-2 m/s. Default 0.05.
        gyro_std_radps: white-noise density of the gyro rate, rad/s/sqrt(Hz). The datasheet
            gives 0.0038 deg/s/sqrt(Hz) (6.6e-5); the default 0.005 (0.29 deg/s/sqrt(Hz))
            covers what the model omits: scale-factor error (+-0.5 % of up to 2 rad/s) and
            a body that rolls on its springs.
        bias_walk_radps: random walk of the gyro bias, rad/s per sqrt(s). Default 1e-4
            (0.006 deg/s/sqrt(s)): slow thermal drift, and room for the filter to keep
            learning the bias instead of freezing its first estimate.
        init_bias_std_radps: prior std of the bias at reset, rad/s: the datasheet's zero-rate
            offset of up to +-0.5 deg/s.
        gate_sigma: fixes whose Mahalanobis distance to the prediction exceeds this are
            rejected (a wrong scan match must not yank the pose). None or inf never rejects
            (the default: the fix is the car's only absolute reference).
        gate_reset_after: after this many rejected fixes in a row the filter trusts the
            localiser again and resets to the next fix (otherwise a lost filter would stay
            lost); 10 is one second at 10 Hz.
    """

    fix_std_m: float = 0.03
    fix_std_yaw_rad: float = 0.02
    speed_std_mps: float = 0.05
    gyro_std_radps: float = 0.005
    bias_walk_radps: float = 1e-4
    init_bias_std_radps: float = math.radians(0.5)
    gate_sigma: float | None = None
    gate_reset_after: int = 10

    def __post_init__(self) -> None:
        for name in ("fix_std_m", "fix_std_yaw_rad", "init_bias_std_radps"):
            value = getattr(self, name)
            if not (_real(value) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive finite number, got {value!r}")
        for name in ("speed_std_mps", "gyro_std_radps", "bias_walk_radps"):
            value = getattr(self, name)
            if not (_real(value) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        g = self.gate_sigma
        if g is not None and not (_real(g) and not math.isnan(g) and g > 0):
            raise ValueError(f"gate_sigma must be None or a number > 0 (inf: never reject), got {g!r}")
        n = self.gate_reset_after
        if not (isinstance(n, int) and not isinstance(n, bool) and n >= 1):
            raise ValueError(f"gate_reset_after must be an integer >= 1, got {n!r}")


class PoseFilter:
    """Car-side EKF: state (x, y, yaw, gyro_bias). Odometry (encoder speed) and the gyro predict;
    the localiser's fixes (x, y, yaw) correct.

    Call :meth:`reset` with the first fix, then :meth:`predict` every control step and
    :meth:`correct` whenever a fix arrives.
    """

    def __init__(self, config: PoseFilterConfig | None = None) -> None:
        self.config = config or PoseFilterConfig()
        c = self.config
        self._R = np.diag([c.fix_std_m ** 2, c.fix_std_m ** 2, c.fix_std_yaw_rad ** 2])
        self._s = np.zeros(4)
        self._P = np.eye(4)
        self._initialised = False
        self._rejected_in_row = 0
        self.rejected_fixes = 0  # total rejected by the gate, for diagnostics

    def reset(self, fix: Sequence[float]) -> None:
        """Starts over at ``fix`` (x, y, yaw) with the fix's noise and the bias prior as covariance."""
        x, y, yaw = _fix(fix)
        c = self.config
        self._s = np.array([x, y, wrap_angle(yaw), 0.0])
        self._P = np.diag([c.fix_std_m ** 2, c.fix_std_m ** 2, c.fix_std_yaw_rad ** 2, c.init_bias_std_radps ** 2])
        self._initialised = True
        self._rejected_in_row = 0

    def predict(self, speed: float, yaw_rate: float, dt: float, lateral_speed: float = 0.0) -> None:
        """Moves the pose by ``speed`` (m/s, encoder) and ``yaw_rate`` (rad/s, raw gyro) over ``dt`` s.

        ``lateral_speed`` is the body origin's sideways speed (m/s, left positive): a car-like
        body with no slip at its rear axle moves its origin sideways at the yaw rate times the
        origin's lever arm from that axle (0.128 m on the QCar 2: 0.2 m/s in a 1.5 rad/s turn).
        """
        for name, value in (("speed", speed), ("yaw_rate", yaw_rate), ("dt", dt), ("lateral_speed", lateral_speed)):
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
        if dt < 0:
            raise ValueError(f"dt must be >= 0 s, got {dt!r}")
        self._require_reset()
        if dt == 0:
            return
        c = self.config
        v, vl = float(speed), float(lateral_speed)
        _, _, yaw, b = self._s
        dyaw = (float(yaw_rate) - b) * dt
        mid = yaw + 0.5 * dyaw
        cm, sm = math.cos(mid), math.sin(mid)
        # The displacement in the map frame and its derivative with respect to the mid heading.
        dx, dy = (v * cm - vl * sm) * dt, (v * sm + vl * cm) * dt
        self._s = np.array([self._s[0] + dx, self._s[1] + dy, wrap_angle(yaw + dyaw), b])
        # Jacobians of the motion with respect to the state (F) and to the inputs v, w (G).
        F = np.eye(4)
        F[0, 2], F[1, 2] = -dy, dx
        F[0, 3], F[1, 3] = 0.5 * dt * dy, -0.5 * dt * dx
        F[2, 3] = -dt
        # Densities: a white input of density q held over dt has variance q^2 / dt, and G is
        # dt times Gs, so the input noise adds dt Gs diag(q^2) Gs^T (no 1/dt for tiny dt).
        Gs = np.array([[cm, -0.5 * dy],
                       [sm, 0.5 * dx],
                       [0.0, 1.0],
                       [0.0, 0.0]])
        Qu = np.diag([c.speed_std_mps ** 2, c.gyro_std_radps ** 2])
        P = F @ self._P @ F.T + dt * (Gs @ Qu @ Gs.T)
        P[3, 3] += c.bias_walk_radps ** 2 * dt
        self._P = 0.5 * (P + P.T)

    def correct(self, fix: Sequence[float]) -> None:
        """Fuses a fix (x, y, yaw); with ``gate_sigma`` set, an outlying fix is rejected instead."""
        z = np.array(_fix(fix))
        self._require_reset()
        c = self.config
        nu = z - self._s[:3]
        nu[2] = wrap_angle(nu[2])
        S = self._P[:3, :3] + self._R
        if c.gate_sigma is not None and math.isfinite(c.gate_sigma):
            d2 = float(nu @ np.linalg.solve(S, nu))
            if d2 > c.gate_sigma ** 2:
                if self._rejected_in_row >= c.gate_reset_after:
                    self.reset(z)  # lost: the localiser has disagreed for too long
                else:
                    self.rejected_fixes += 1
                    self._rejected_in_row += 1
                return
        self._rejected_in_row = 0
        K = np.linalg.solve(S, self._P[:, :3].T).T  # P H^T S^-1, S symmetric
        s = self._s + K @ nu
        s[2] = wrap_angle(s[2])
        self._s = s
        IKH = np.eye(4)
        IKH[:, :3] -= K
        P = IKH @ self._P @ IKH.T + K @ self._R @ K.T
        self._P = 0.5 * (P + P.T)

    @property
    def pose(self) -> np.ndarray:
        """(3,) copy: x, y (m), yaw (rad) in (-pi, pi]."""
        return self._s[:3].copy()

    @property
    def gyro_bias(self) -> float:
        """Estimated gyro zero-rate offset, rad/s (subtracted from the raw rate)."""
        return float(self._s[3])

    @property
    def covariance(self) -> np.ndarray:
        """(4, 4) copy of the state covariance (x, y, yaw, bias)."""
        return self._P.copy()

    @property
    def initialised(self) -> bool:
        return self._initialised

    def _require_reset(self) -> None:
        if not self._initialised:
            raise RuntimeError("PoseFilter has no pose yet: call reset(fix) first")


def _real(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _fix(fix: Sequence[float]) -> tuple[float, float, float]:
    values = np.asarray(fix, dtype=float).reshape(-1)
    if values.shape != (3,) or not np.all(np.isfinite(values)):
        raise ValueError(f"a fix is three finite numbers (x, y, yaw), got {fix!r}")
    return float(values[0]), float(values[1]), float(values[2])
