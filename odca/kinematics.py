"""The kinematic branch: the last trusted distance, advanced by the car's own odometry.

The target is static, so once a measurement is trusted its place in the camera frame only
moves by the car's own motion. The branch keeps that place, (z forward along the optical
axis, y to the left), and per step moves the camera by the wheel speed along its axis, by
the yaw rate x the camera's lever arm sideways (no slip at the rear axle, the turning
centre) and turns it by the yaw rate:

    turn by -omega dt / 2;  z -= v dt,  y -= omega L dt;  turn by -omega dt / 2.

d_kin is z: a depth along the optical axis, the quantity depth and LiDAR report. On a
straight approach it falls by exactly v dt whatever the bearing; on a curve the bearing at
the anchor (y = z tan(bearing)) sets how the turn moves it.

Its standard deviation starts at ``anchor_std_m`` when the branch is anchored and grows
with the distance travelled (encoder scale, slip), with time (what the model leaves out) and,
for a branch anchored with no bearing (a LiDAR return while the camera detects nothing), with
the angle turned times how far its guessed lateral place may be off: without a bearing a turn
moves d_kin by an unknown amount, so in turns such a branch soon says nothing. Past
``max_std_m``, or once the target would be behind the camera, the branch is lost and says
nothing (NaN) until the next trusted measurement.

Once the target's bearing passes ``max_bearing_rad`` the car has passed it: the branch is lost
too. Else a LiDAR return beside the car could re-anchor a point carried metres to the side, and
the next left turn swung it metres "ahead" (seen offline: a 6 m phantom that outvoted the next
sign's depth).

Beside it runs the **baseline**: the same point, anchored at the target's first
*confirmed* measurement with a bearing (two witnesses agreeing: a depth alone may already be
corrupted; a bearing, because a point placed at a guessed one leaves the target in the first
hard turn) and then moved by odometry alone, never re-anchored until it is lost (its std grows by
``drift_travel_std`` per metre; it is lost with the branch, since a point model carried
through long unseen turns drifts past its std). Re-anchoring is what lets the branch follow the
target, and also what a slow, consistent drift of depth and LiDAR together (a frustum
spoof) would exploit: each anchor within the tolerance of the last. The baseline bounds
that: a measurement off the baseline by more than ``tau + n_sigma * std`` has drifted away
from where odometry puts the target (:meth:`drifted`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["KinematicsConfig", "KinematicBranch"]

#: The QCar 2's camera ahead of its rear axle, m (camera at +0.095 m, rear axle at -0.128 m on the body).
QCAR2_CAMERA_LEVER_M = 0.223


@dataclass(frozen=True)
class KinematicsConfig:
    """The kinematic branch's settings.

    Attributes:
        enabled: run the branch (False: ODCA without kinematics, the ablation).
        witness: the branch votes in the gate (False: the paper's two-witness gate, where
            only the LiDAR can confirm the depth; the branch still bases repairs).
        camera_lever_m: the camera's distance ahead of the rear axle, m.
        anchor_std_m: std of a trusted measurement, m.
        travel_std: std growth per metre travelled (odometry scale error and slip).
        time_std_mps: std growth per second.
        max_std_m: beyond this std the branch is lost, m.
        n_sigma: a witness agrees with the branch within ``tau + n_sigma * std``.
        drift_travel_std: the baseline's std growth per metre travelled (None: no baseline,
            the branch as it was before issue 23).
        camera_frame_s: the camera's frame period, s (30 Hz on the QCar 2). The loop steps at
            50 Hz, so perception holds a frame's depth over a step; a depth repeated within one
            period is that old, and :meth:`drifted` gives it the distance driven since.
        max_bearing_rad: past this bearing the target has been passed and the branch is lost
            (None: only once it is behind the camera). Twice the RGB camera's half field of view
            (34.7 deg, qcar2.md): a 360-degree LiDAR may track a sign a turn is bringing into view.
    """

    enabled: bool = True
    witness: bool = True
    camera_lever_m: float = QCAR2_CAMERA_LEVER_M
    anchor_std_m: float = 0.03
    travel_std: float = 0.04
    time_std_mps: float = 0.01
    max_std_m: float = 0.4
    n_sigma: float = 3.0
    drift_travel_std: float | None = 0.02
    camera_frame_s: float = 1.0 / 30.0
    max_bearing_rad: float | None = 1.2

    def __post_init__(self) -> None:
        if self.max_bearing_rad is not None and not (
                isinstance(self.max_bearing_rad, (int, float)) and 0.0 < self.max_bearing_rad < math.pi / 2):
            raise ValueError(f"kinematics max_bearing_rad must be in (0, pi/2) or None, got {self.max_bearing_rad!r}")
        if self.drift_travel_std is not None and not (
                isinstance(self.drift_travel_std, (int, float)) and 0.0 <= self.drift_travel_std <= 1.0):
            raise ValueError(f"kinematics drift_travel_std must be in [0, 1] or None, got {self.drift_travel_std!r}")
        for name, lo, hi in (("camera_lever_m", -2.0, 2.0), ("anchor_std_m", 0.0, 1.0), ("travel_std", 0.0, 1.0),
                             ("time_std_mps", 0.0, 1.0), ("max_std_m", 0.01, 10.0), ("n_sigma", 0.0, 10.0),
                             ("camera_frame_s", 0.0, 1.0)):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and lo <= value <= hi):
                raise ValueError(f"kinematics {name} must be in [{lo}, {hi}], got {value!r}")


class KinematicBranch:
    """One target's kinematic distance: :meth:`predict` each step, :meth:`anchor` on a trusted measurement."""

    def __init__(self, config: KinematicsConfig) -> None:
        self.config = config
        self.reset()

    def reset(self) -> None:
        self.z = math.nan
        self.y = 0.0
        self.std = math.nan
        self.lidar_only = False  # anchored on a LiDAR no depth has agreed with (see anchor)
        self.size_only = False  # anchored on the size witness alone (see anchor)
        self.depth_only = False  # anchored on a depth no other witness confirmed (see anchor)
        self.y_std = 0.0  # how far the lateral place may be off: an anchor with no bearing guesses it
        self._lose_baseline()

    def _lose_baseline(self) -> None:
        self.base_z, self.base_y, self.base_std = math.nan, 0.0, math.nan

    @property
    def alive(self) -> bool:
        return math.isfinite(self.z)

    @property
    def distance(self) -> float:
        """d_kin, m (NaN when the branch is lost or was never anchored)."""
        return self.z

    def tolerance(self, tau_m: float) -> float:
        """How far a witness may lie from d_kin and still agree with it, m."""
        return tau_m + self.config.n_sigma * self.std

    @property
    def baseline(self) -> float:
        """The baseline's distance, m (NaN without one)."""
        return self.base_z

    def drifted(self, distance: float, tau_m: float, age_m: float = 0.0) -> bool:
        """Whether a measurement lies off the baseline by more than its tolerance (False without one).
        ``age_m``: the distance driven since the measurement was taken (a held camera frame)."""
        if not math.isfinite(self.base_z) or not math.isfinite(distance):
            return False
        return abs(distance - self.base_z) > tau_m + self.config.n_sigma * self.base_std + age_m

    def predict(self, speed: float, yaw_rate: float, dt: float, target_speed_std_mps: float = 0.0) -> float:
        """Moves the target by the car's motion over ``dt``; returns the change of d_kin (NaN when lost).
        ``target_speed_std_mps``: how uncertain the target's own speed is (0: a standing target, a
        sign's); the baseline's spread grows with it, for it moves the target by what ``speed`` omits."""
        c = self.config
        if math.isfinite(self.base_z):
            self.base_z, self.base_y = advance(self.base_z, self.base_y, speed, yaw_rate, dt, c.camera_lever_m)
            self.base_std += (c.drift_travel_std or 0.0) * abs(speed) * dt + c.time_std_mps * dt
            self.base_std += target_speed_std_mps * dt
            if self.base_std > c.max_std_m or self.base_z <= 0.0:
                self._lose_baseline()
        if not self.alive:
            self._lose_baseline()
            return math.nan
        z, y = advance(self.z, self.y, speed, yaw_rate, dt, c.camera_lever_m)
        change = z - self.z
        self.z, self.y = z, y
        # A turn moves d_kin by about its angle times the lateral place: an unknown place, an unknown change.
        self.std += c.travel_std * abs(speed) * dt + c.time_std_mps * dt + abs(yaw_rate * dt) * self.y_std
        if self.std > c.max_std_m or self.z <= 0.0 or self._passed():
            self.z, self.y, self.std = math.nan, 0.0, math.nan
            self.lidar_only = self.size_only = self.depth_only = False
        return change

    def _passed(self) -> bool:
        limit = self.config.max_bearing_rad
        return limit is not None and abs(math.atan2(self.y, self.z)) > limit

    def anchor(self, distance: float, bearing: float = math.nan, confirmed: bool = True,
               lidar_only: bool = False, std: float | None = None, size_only: bool = False,
               depth_only: bool = False) -> None:
        """Restarts the branch at a trusted distance (m) and, if known, the target's bearing (rad, left
        positive); a ``confirmed`` one (two witnesses agree) with a bearing also starts the baseline
        if there is none. ``lidar_only``: the anchor rests on a LiDAR track that no depth has agreed with.
        ``std``: the anchor's std, m (default ``anchor_std_m``, a range sensor's).
        ``size_only``: the anchor rests on the size witness alone (:meth:`fuse` refines it).
        ``depth_only``: the anchor rests on a depth that nothing confirmed (a first sight): d_kin
        then only echoes that depth and is no witness against it."""
        self.lidar_only = bool(lidar_only)
        self.size_only = bool(size_only)
        self.depth_only = bool(depth_only)
        located = math.isfinite(bearing) and abs(bearing) < 1.5
        if located:
            self.y, self.y_std = distance * math.tan(bearing), 0.0
        elif self.alive and self.z > 0.0:  # keep the bearing the branch had, and its doubt
            self.y, self.y_std = distance * self.y / self.z, self.y_std * distance / self.z
        else:  # straight ahead, as a guess: anywhere the limit allows
            self.y, self.y_std = 0.0, distance * math.tan(self.config.max_bearing_rad or 1.2)
        self.z = distance
        self.std = self.config.anchor_std_m if std is None else max(float(std), self.config.anchor_std_m)
        # The baseline is a place, so it starts only where the bearing was measured: a point placed
        # at a guessed bearing drifts off the target in the first hard turn (seen offline).
        if confirmed and located and self.config.drift_travel_std is not None and not math.isfinite(self.base_z):
            self.base_z, self.base_y, self.base_std = self.z, self.y, self.std

    def fuse(self, distance: float, std: float) -> None:
        """Refines a branch that rests on the size witness alone with a new size measurement (m,
        its std m): the two weighted by their variances, as a Kalman update. The std never
        falls below ``anchor_std_m``: the size's calibration error does not average out."""
        if not (self.alive and self.size_only and math.isfinite(distance) and math.isfinite(std) and std > 0):
            return
        w = self.std ** 2 / (self.std ** 2 + std ** 2)
        scale = (self.z + w * (distance - self.z)) / self.z
        self.z, self.y = self.z * scale, self.y * scale  # along the same bearing
        self.std = max(math.sqrt((1.0 - w) * self.std ** 2), self.config.anchor_std_m)


def advance(z: float, y: float, speed: float, yaw_rate: float, dt: float, lever_m: float) -> tuple[float, float]:
    """A static point (z forward, y left, camera frame) after the camera moves for ``dt``: half the
    turn, the step's translation, the other half (second-order accurate on an arc)."""
    half = 0.5 * yaw_rate * dt
    c, s = math.cos(half), math.sin(half)
    z, y = c * z + s * y, -s * z + c * y
    z, y = z - speed * dt, y - yaw_rate * lever_m * dt
    return c * z + s * y, -s * z + c * y
