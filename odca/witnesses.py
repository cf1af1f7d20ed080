"""The sequential part of ODCA's step (:mod:`racf.odca.online`): the kinematic branch, the gate's
vote and the anchoring, and the per-step bound on a repair. The delta head does not feed back, so
a series' verdicts are known before the head runs; the online and the batched paths share this."""

from __future__ import annotations

import math
import numpy as np

from racf.odca.features import MAX_RANGE_M
from racf.odca.gate import BASELINE, DEPTH, KIN, LIDAR, LIDAR_KIN, SIZE, vote
from racf.odca.kinematics import KinematicBranch

__all__ = ["Witnesses", "bounded"]


class Witnesses:
    """The sequential part of a step: kinematic branch, vote and anchoring (no head: it does
    not feed back, so a series' verdicts are known before the head runs)."""

    def __init__(self, config) -> None:
        """``config``: the online module's ``ODCAConfig`` (its kinematics and gate settings)."""
        self.config = config
        self.branch = KinematicBranch(config.kinematics)
        self.last_size = math.nan
        self.last_depth, self.held_s, self.held_m = math.nan, 0.0, 0.0

    def reset(self) -> None:
        self.branch.reset()
        self.last_size = math.nan
        self.last_depth, self.held_s, self.held_m = math.nan, 0.0, 0.0

    def depth_age(self, d: float, motion: float, dt: float) -> float:
        """The distance driven since this depth's frame, m: perception holds a camera frame's
        depth over the loop's faster steps, so a depth equal to the last step's is that frame's,
        as long as it has been held for less than one frame period (longer: not a frame's hold)."""
        self.held_s, self.held_m = self._held_after(d, motion, dt)
        self.last_depth = d
        return self._age(self.held_s, self.held_m)

    def peek_depth_age(self, d: float, motion: float, dt: float) -> float:
        """:meth:`depth_age` for a step that may not happen: changes nothing."""
        return self._age(*self._held_after(d, motion, dt))

    def _held_after(self, d: float, motion: float, dt: float) -> tuple[float, float]:
        """(seconds, metres) the depth will have been held after a step with depth ``d``."""
        if d == d and d == self.last_depth:
            return self.held_s + dt, self.held_m + abs(motion)
        return 0.0, 0.0

    def _age(self, held_s: float, held_m: float) -> float:
        return held_m if held_s < self.config.kinematics.camera_frame_s else 0.0

    def lidar_unconfirmed(self, l: float, lidar_confirmed: bool, branch: KinematicBranch) -> bool:
        """Whether the LiDAR side of the vote is one witness: a track no depth confirmed, or a
        branch anchored on such a track alone."""
        return (self.config.kinematics.enabled and branch.alive and branch.lidar_only) or (
            l == l and not lidar_confirmed)

    def step(self, d, c, l, v, yaw_rate, bearing, mu, dt, lidar_confirmed=True, size=math.nan, size_std=math.nan,
             moving_std=None):
        """Returns (source, base, lidar_trusted, d_kin, kin_std, motion) for one sanitised step.
        ``lidar_confirmed``: whether a depth ever agreed with the LiDAR's track (perception's word).
        ``size``, ``size_std``: the size witness and its std (NaN: none).
        ``moving_std``: for a target that moves (a car ahead; ``v`` is then the closing speed), how
        uncertain its own speed is, m/s (None: a standing target, a sign): the baseline spreads with it."""
        cfg = self.config
        branch = self.branch
        on = cfg.kinematics.enabled
        motion = branch.predict(v, yaw_rate, dt, 0.0 if moving_std is None else moving_std) if on else math.nan
        if not motion == motion:
            motion = -v * dt  # no branch: a straight approach's change
        k, k_std = branch.distance, branch.std
        lidar_only = on and branch.alive and branch.lidar_only
        size_tol = cfg.gate.size_tolerance(size_std)
        # A box bigger than a car where the range witnesses place it may be a picture (a phantom), but the
        # same vote is what a depth patch that drew the LiDAR's track along looks like: the box keeps its
        # veto for a moving target too (dropping it let the patch through, 0.97 -> 0.37 collision-free).
        # Telling the two apart needs their history, which the supervisor's reading chain keeps.
        source, base, lidar_trusted = vote(d, c, l, k, branch.tolerance(cfg.gate.tau_m) if k == k else math.nan, mu,
                                           cfg.gate, cfg.kinematics.witness,
                                           lidar_unconfirmed=self.lidar_unconfirmed(l, lidar_confirmed, branch),
                                           size=size, size_tol=size_tol, k_echoes_depth=on and branch.depth_only)
        new_size = size == size and size != self.last_size  # perception holds a frame's box between frames
        self.last_size = size
        age_m = self.depth_age(d, motion, dt)
        if on and source in (DEPTH, LIDAR, LIDAR_KIN) and branch.drifted(base, cfg.gate.tau_m,
                                                                           age_m if source == DEPTH else 0.0):
            source, base, lidar_trusted = BASELINE, branch.baseline, False
        elif on and source == DEPTH and (lidar_trusted or lidar_only or branch.size_only or not branch.alive):
            by_size = size == size and abs(d - size) <= size_tol
            branch.anchor(d, bearing, confirmed=lidar_trusted, depth_only=not (lidar_trusted or by_size))
        elif on and source in (LIDAR, LIDAR_KIN):
            branch.anchor(l, bearing, confirmed=source == LIDAR_KIN and lidar_confirmed, lidar_only=not lidar_confirmed)
        elif on and source == SIZE:
            # The size alone anchors the branch at first sight (a blackout the LiDAR cannot confirm against).
            branch.anchor(size, bearing, confirmed=False, std=size_std, size_only=True)
        elif on and source == KIN and branch.size_only and new_size and abs(size - k) <= size_tol:
            branch.fuse(size, size_std)
        return source, base, lidar_trusted, k, k_std, motion


def bounded(values: np.ndarray, motion: np.ndarray, bound: float, prev: float, first: np.ndarray | None = None,
             free: np.ndarray | None = None) -> np.ndarray:
    """Each value kept within ``bound`` of (the previous output + the car's motion); a NaN
    (no target) or a segment's ``first`` step starts afresh. ``free`` steps (a depth the gate
    passed) are kept as they are and the bound restarts from them: Proposition 1 holds for the
    output, not only for the vote (bounding them changed clean depth just after a repair)."""
    out = values.copy()
    for t in range(len(out)):
        if first is not None and first[t]:
            prev = math.nan
        x = out[t]
        if x == x and prev == prev and not (free is not None and free[t]):
            centre = prev + motion[t]
            x = min(max(x, centre - bound), centre + bound)
            out[t] = min(max(x, 0.0), MAX_RANGE_M)
        prev = out[t]
    return out
