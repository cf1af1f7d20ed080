"""The LiDAR reference l(t): the detected target's depth along the camera's optical axis,
measured by the 2D LiDAR and tracked with odometry.

:class:`LidarTargetTracker` implements the protocol's ``l`` (docs/protocol.md):

1. **Predict** (every control step). The tracked target is a point in the body frame (x
   forward, y left, origin at the car's reference point). Each step moves it by the car's
   odometry over ``dt``: the car advances ``speed * dt`` (plus ``lateral_speed * dt``
   sideways) along its mean heading and turns ``yaw_rate * dt``, and the point is written in
   the new body frame. Targets (stop signs, crates) are static, so this is the whole motion
   model. It is also the age compensation of the 10 Hz scans: between scans (four control
   steps out of five at 50 Hz) the reported value is the last supported position carried
   forward by odometry, so it is valid for the current step, not for the scan's.
2. **Measure** (on a step with a new scan). The returns of the beams within
   ``sector_half_angle_rad`` of forward (a LiDAR-frame sector that holds every return ahead
   of the camera within that bearing of its optical axis) and range <= ``max_range_m`` are
   segmented with :func:`~racf.controllers.lidar_segmentation.segment_scan` (DBSCAN with
   ``min_samples=1``, ``eps_m``), and each cluster is described in the camera frame:
   centroid (its x is the cluster's depth along the optical axis: the mean fitted the
   simulator's d_true of the sign's plate and of a crate's near face slightly better than
   the median, 1.1 vs 1.14 cm RMS per scan on tests/data/lidar_scans.npz), bearing span
   (min and max bearing of its points, widened by half a beam step at its range) and width
   across the line of sight to the centroid (extent of its points, with one to two beam
   spacings of sampling tolerance). Clusters behind the camera (depth <= 0) never count.
   The beams' ages are compensated: the LiDAR sweeps, so each beam was taken at its own time,
   up to a revolution (0.1 s) before the step the scan is handed over on
   (``step(beam_age_s=...)``). A cluster counts as seen at the mean age of its beams, and its
   centroid and bearing span are carried forward to this step by odometry over that age
   (as in the prediction), so association and update use positions valid now.
3. **Associate.** With a detection, a candidate's widened span (plus
   ``bearing_margin_rad``) must hold the detection's centre bearing and its width must fit
   the target kind. With a track, a candidate must also lie within the gate around the
   predicted position (``gate_radius_m + gate_growth_mps * time since support``), and the
   nearest one wins. Without a track, the detection starts one: the box's width implied at
   the cluster's depth must fit the kind too (this rejects background far behind the box),
   and the winner is the cluster whose bearing is closest to the detection's, plus a
   penalty for the part of its span outside the box (so a wall fragment straddling the box
   edge loses to the target inside it). Without a detection only a gated candidate of an
   existing track counts: a track is never started without a detection.
4. **Update.** A supported track moves to the measured point (exponentially smoothed with
   weight ``smoothing`` when the previous scan supported it too). When no candidate fits,
   the value is NaN on that step and until the next supported scan (never another object),
   but the track coasts on odometry so it can be re-acquired inside its growing gate. After
   ``drop_after_s`` (default 1 s) without support the track is dropped; the value is also
   NaN once the last support is older than ``report_max_age_s`` (missing scans).

The value is NaN before any track. Changing ``target`` between "sign" and "obstacle"
drops the track. Pure numpy/scipy: no simulator imports.
"""

from __future__ import annotations

import math

import numpy as np

from racf.controllers.lidar_segmentation import segment_scan
from racf.controllers.lidar_target_config import TARGET_KINDS, LidarTargetConfig, LidarTargetState

__all__ = ["TARGET_KINDS", "LidarTargetConfig", "LidarTargetState", "LidarTargetTracker"]

class LidarTargetTracker:
    """l(t) for one target: see the module docstring.

    Args:
        config: geometry, association and track keeping; defaults fit the QCar 2.

    Example:
        >>> import numpy as np
        >>> tracker = LidarTargetTracker(LidarTargetConfig())
        >>> scan = np.full(360, np.inf)
        >>> scan[[359, 0, 1]] = 1.5 / np.cos(np.radians([-1.0, 0.0, 1.0]))  # a plate 1.5 m ahead
        >>> l = tracker.step(scan=scan, detection_bearing=-0.021, detection_span=(0.0, -0.045),
        ...                  target="sign", speed=0.0, yaw_rate=0.0, dt=0.02)
        >>> round(l, 3)
        1.393
    """

    def __init__(self, config: LidarTargetConfig | None = None) -> None:
        self.config = config or LidarTargetConfig()
        c = self.config
        # The LiDAR's position in the camera frame, (2, 1) m: a point's camera-frame (x, y)
        # is its LiDAR-frame (x, y) plus this (both level, both looking along body +x).
        self._offset = np.array([[c.lidar_position_m[0] - c.camera_position_m[0]],
                                 [c.lidar_position_m[1] - c.camera_position_m[1]]])
        self._n_beams = -1
        self._sector_idx = np.zeros(0, np.int64)
        self._cos_sin = np.zeros((2, 0))
        self._beam_step = 0.0
        self.reset()

    def reset(self) -> None:
        """Forgets the track (start of an episode)."""
        self._pos: tuple[float, float] | None = None  # body frame, m
        self._kind: str | None = None
        self._age = math.inf  # since support, s
        self._reporting = False  # the latest scan since the track started supported it
        self._n_points = 0
        self._n_clusters = 0
        self._value = math.nan
        self._depth_confirmed = False

    @property
    def depth_confirmed(self) -> bool:
        """Whether the camera's depth has agreed (within ``start_depth_tolerance_m``) with the
        track since it started. A track started while the depth was missing may sit on the
        background behind a sign the scan plane misses; the fusion then counts it as one witness."""
        return self._pos is not None and self._depth_confirmed

    @property
    def state(self) -> LidarTargetState:
        """The track after the last step."""
        if self._pos is None:
            return LidarTargetState(False, None, (math.nan, math.nan), self._value, False, math.inf, math.nan,
                                    0, self._n_clusters)
        cx, cy = self.config.camera_position_m
        return LidarTargetState(True, self._kind, (self._pos[0] - cx, self._pos[1] - cy), self._value,
                                math.isfinite(self._value), self._age, self._gate(), self._n_points,
                                self._n_clusters)

    def step(self, *, scan: np.ndarray | None, detection_bearing: float,
             detection_span: tuple[float, float] | None, target: str, speed: float, yaw_rate: float,
             dt: float, lateral_speed: float = 0.0, detection_depth: float = math.nan,
             beam_age_s: np.ndarray | float | None = None, detection_height: float = math.nan) -> float:
        """Advances one control step and returns l.

        Args:
            scan: (N,) ranges of a scan that arrived on this step, metres (beam i at
                2 pi i / N counter-clockwise from forward; inf, NaN or <= 0 = no return);
                None on steps without a new scan.
            detection_bearing: bearing of the detection's centre from the optical axis,
                rad, left positive; NaN without a detection.
            detection_span: (left, right) bearings of the detection box's edges, rad, or None.
            target: "sign", "obstacle" or "vehicle", the kind the detection is of.
            speed: forward speed of the car's reference point, m/s.
            yaw_rate: rad/s, counter-clockwise positive.
            dt: time since the previous step, s.
            lateral_speed: body-frame sideways speed of the reference point, m/s (left).
            detection_depth: the camera's depth distance of the detection, m (NaN: none).
                Used only to start a track: the first cluster must agree with it within
                ``start_depth_tolerance_m``. When a sign is seen so obliquely that no beam
                hits its plate, the cluster inside its box is whatever stands behind it.
            beam_age_s: how long before this step each beam of ``scan`` was taken, s (>= 0):
                an (N,) array (a sweeping LiDAR: one age per beam), one float for all beams,
                or None (all taken now). Each cluster is carried forward by the odometry
                (``speed``, ``lateral_speed``, ``yaw_rate``) over its beams' mean age.
            detection_height: the detection box's height per metre of depth (its pixel
                height / fy; NaN: unknown). Used only to start a track: the box may not be
                taller than ``box_height_max_m`` at the cluster's depth. Without a depth (a
                blacked-out one), it is what keeps a track off the background behind a sign.

        Returns:
            Depth of the tracked target along the camera's optical axis, metres; NaN before
            any track, on and after a scan that does not support it, and once the last
            support is older than ``report_max_age_s``.
        """
        if target not in TARGET_KINDS:
            raise ValueError(f"target must be one of {TARGET_KINDS}, got {target!r}")
        if not (dt >= 0 and math.isfinite(dt)):
            raise ValueError(f"dt must be a finite number >= 0 s, got {dt!r}")
        ages = _beam_ages(beam_age_s, scan)
        if self._pos is not None and target != self._kind:
            self.reset()
        c = self.config
        detection_depth += c.scan_behind_m(target)  # where the scan plane cuts what the camera sees
        if self._pos is not None:
            self._pos = _move(self._pos, speed * dt, lateral_speed * dt, yaw_rate * dt)
            self._age += dt
        if scan is not None:
            det = detection_bearing is not None and math.isfinite(detection_bearing)
            self._measure(scan, detection_bearing if det else None, detection_span if det else None, target,
                          detection_depth if det else math.nan, ages, (speed, lateral_speed, yaw_rate),
                          detection_height if det else math.nan)
        if self._pos is not None and self._age > c.drop_after_s:
            self.reset_track()
        if self._pos is not None and self._reporting and self._age <= c.report_max_age_s:
            self._value = self._pos[0] - c.camera_position_m[0] - c.scan_behind_m(self._kind)
        else:
            self._value = math.nan
        return self._value

    def reset_track(self) -> None:
        """Drops the track but keeps the last scan's cluster count (for the state)."""
        n = self._n_clusters
        self.reset()
        self._n_clusters = n

    # -- internals ------------------------------------------------------------------------
    def _gate(self) -> float:
        return self.config.gate_radius_m + self.config.gate_growth_mps * self._age

    def _measure(self, scan: np.ndarray, bearing: float | None, span: tuple[float, float] | None,
                 target: str, depth: float, ages: np.ndarray | float | None,
                 odometry: tuple[float, float, float], height: float = math.nan) -> None:
        """Associates one scan with the track (or starts one) and updates it.

        Args:
            ages: the beams' ages (see ``step(beam_age_s=...)``), checked; None = all now.
            odometry: (speed m/s, lateral speed m/s, yaw rate rad/s) to carry clusters forward.
        """
        c = self.config
        cl = self._clusters(scan, ages)
        self._n_clusters = 0 if cl is None else cl[0].shape[1]
        tracked = self._pos is not None
        if cl is None or (not tracked and bearing is None):
            self._reporting = False
            return
        mean, lo, hi, half, counts, starts, pts, age = cl
        ox, oy = mean[0], mean[1]  # as measured: the width check's line of sight
        mx, my = ox, oy
        if age is not None:
            # Carry each centroid forward from when its beams were taken to now, as the
            # prediction carries the track; the span turns with the centroid's bearing.
            speed, lateral, yaw_rate = odometry
            cx, cy = c.camera_position_m
            moved = np.array([_move((x + cx, y + cy), speed * a, lateral * a, yaw_rate * a)
                              for x, y, a in zip(ox.tolist(), oy.tolist(), age.tolist())]).T
            mx, my = moved[0] - cx, moved[1] - cy
            turn = np.arctan2(my, mx) - np.arctan2(oy, ox)
            turn = (turn + math.pi) % (2 * math.pi) - math.pi
            lo, hi = lo + turn, hi + turn
        # Vectorised pre-selection; the width check below runs on the few survivors.
        if bearing is not None:
            pad = half + c.bearing_margin_rad
            ok = (lo - pad <= bearing) & (hi + pad >= bearing) & (mx > 0)
        else:
            ok = mx > 0
        if tracked:
            px, py = self._pos[0] - c.camera_position_m[0], self._pos[1] - c.camera_position_m[1]
            dist = np.hypot(mx - px, my - py)
            ok &= dist <= self._gate()
        picked, best = -1, math.inf
        w_lo, w_hi = c.width_m(target)
        if span is not None:
            left, right = max(span), min(span)
            box_lo, box_hi = c.box_width_m(target)
            tan_span = math.tan(left) - math.tan(right)
        for k in np.flatnonzero(ok).tolist():
            x, y = float(mx[k]), float(my[k])
            # The width across the line of sight, from the points as measured and the centroid
            # as measured: carrying them forward (a small translation and turn) would not
            # change it, so only the centroid is moved.
            x0, y0 = float(ox[k]), float(oy[k])
            rho = math.hypot(x0, y0)
            spacing = 2.0 * float(half[k]) * rho  # beam spacing at the cluster's range, m
            s, e = int(starts[k]), int(starts[k] + counts[k])
            sin_b, cos_b = y0 / rho, x0 / rho
            across = (cos_b * pts[1, s:e] - sin_b * pts[0, s:e]).tolist()
            extent = max(across) - min(across)
            if extent > w_hi + spacing or extent + 2.0 * spacing < w_lo:
                continue
            if tracked:
                score = float(dist[k])
            else:
                if span is not None:
                    implied = x * tan_span  # width of the box at the cluster's depth, m
                    if not box_lo <= implied <= box_hi:
                        continue
                if abs(x - depth) > c.start_depth_tolerance_m:  # False when depth is NaN
                    continue
                if x * height > c.box_height_max_m(target):  # False when height is NaN
                    continue
                score = abs(math.atan2(y, x) - bearing)
                if span is not None:
                    score += max(float(hi[k] + half[k]) - left, 0.0) + max(right - float(lo[k] - half[k]), 0.0)
            if score < best:
                picked, best = k, score
        if picked < 0:
            self._reporting = False
            return
        zx = float(mx[picked]) + c.camera_position_m[0]
        zy = float(my[picked]) + c.camera_position_m[1]
        if tracked and self._reporting:
            a = c.smoothing
            zx = self._pos[0] + a * (zx - self._pos[0])
            zy = self._pos[1] + a * (zy - self._pos[1])
        if not tracked:
            self._depth_confirmed = False
        if math.isfinite(depth) and abs(float(mx[picked]) - depth) <= c.start_depth_tolerance_m:
            self._depth_confirmed = True
        self._pos = (zx, zy)
        self._kind = target
        self._age = 0.0
        self._reporting = True
        self._n_points = int(counts[picked])

    def _clusters(self, scan: np.ndarray, ages: np.ndarray | float | None = None):
        """Clusters of the forward sector's returns, camera frame; None without returns.

        Args:
            scan: (N,) ranges, m.
            ages: (N,) ages of the beams, s, one age for all, or None.

        Returns:
            ``(mean, lo, hi, half, counts, starts, points, age)``: (2, K) centroids (x, y),
            m; (K,) min and max bearing of the points, rad; (K,) half a beam step at the
            cluster's range, as a bearing, rad; (K,) point counts; (K,) offsets of each
            cluster's points in ``points``; (3, M) the points grouped by cluster: camera
            frame x, y and LiDAR range, m; (K,) mean age of each cluster's beams, s (None
            when ``ages`` is None).
        """
        c = self.config
        scan = np.asarray(scan)
        if scan.ndim != 1 or scan.size < 8:
            raise ValueError(f"scan must be a 1-D array of >= 8 ranges, got shape {scan.shape}")
        if scan.size != self._n_beams:
            self._set_beams(scan.size)
        r = scan[self._sector_idx]
        ok = (r <= c.max_range_m) & (r > 0)  # NaN and inf fail (comparisons do not warn)
        r = r[ok].astype(np.float64)
        if r.size == 0:
            return None
        lidar = r * self._cos_sin[:, ok]  # (2, M) in the LiDAR frame
        labels = segment_scan(lidar.T, c.eps_m, beam_step_rad=self._beam_step)
        order = np.argsort(labels, kind="stable")
        counts = np.bincount(labels)
        starts = np.cumsum(counts) - counts
        pts = np.empty((3, r.size))
        pts[:2] = lidar
        pts[:2] += self._offset  # camera frame
        pts[2] = r
        pts = pts[:, order]
        sums = np.add.reduceat(pts, starts, axis=1) / counts
        bearing = np.arctan2(pts[1], pts[0])
        lo = np.minimum.reduceat(bearing, starts)
        hi = np.maximum.reduceat(bearing, starts)
        half = (0.5 * self._beam_step) * sums[2] / np.hypot(sums[0], sums[1])
        if ages is None:
            age = None
        elif isinstance(ages, float):
            age = np.full(counts.size, ages)
        else:
            age = np.add.reduceat(ages[self._sector_idx][ok][order], starts) / counts
        return sums[:2], lo, hi, half, counts, starts, pts, age

    def _set_beams(self, n: int) -> None:
        """Caches the beams of the forward sector, in increasing angle (-sector..+sector)."""
        step = 2 * math.pi / n
        # A point ahead of the camera (x > 0) at camera bearing beta is, seen from a LiDAR
        # behind the camera at (-a, -b) in the camera frame, x (1, tan beta) + (a, b): its
        # LiDAR bearing lies between beta and atan2(b, a). So that sector holds them all.
        a, b = -self._offset[0, 0], -self._offset[1, 0]
        half = max(self.config.sector_half_angle_rad, math.atan2(abs(b), a)) if a > 0 else math.pi
        m = int(half / step + 1e-9)
        idx = np.concatenate([np.arange(n - m, n), np.arange(0, m + 1)]) if 2 * m + 1 < n else np.arange(n)
        angles = idx * step
        self._n_beams = n
        self._sector_idx = idx
        self._cos_sin = np.stack([np.cos(angles), np.sin(angles)])
        self._beam_step = step


def _beam_ages(value, scan) -> np.ndarray | float | None:
    """``step``'s ``beam_age_s`` checked: None, a float, or a float64 array shaped like ``scan``."""
    if value is None:
        return None
    try:
        ages = None if isinstance(value, bool) else np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        ages = None
    if ages is not None and ages.ndim == 0:
        a = float(ages)
        if math.isfinite(a) and a >= 0:
            return a
    elif (ages is not None and ages.ndim == 1 and (scan is None or ages.shape == np.shape(scan))
          and np.isfinite(ages).all() and (ages >= 0).all()):
        return ages
    shape = "" if scan is None else f" of shape {np.shape(scan)} like scan"
    got = f"an array of shape {ages.shape}" if ages is not None and ages.ndim else repr(value)
    raise ValueError(f"beam_age_s must be None, a float >= 0 or an array{shape} of finite ages >= 0 s, "
                     f"got {got}")


def _move(pos: tuple[float, float], forward: float, sideways: float, turn: float) -> tuple[float, float]:
    """A static point in the body frame after the car moves (forward, sideways) along its
    mean heading and turns by ``turn`` radians."""
    h = 0.5 * turn
    ch, sh = math.cos(h), math.sin(h)
    tx = forward * ch - sideways * sh
    ty = forward * sh + sideways * ch
    dx, dy = pos[0] - tx, pos[1] - ty
    c, s = math.cos(turn), math.sin(turn)
    return (c * dx + s * dy, -s * dx + c * dy)
