"""Where the target can be: the interval its last vouched place and the envelope allow.

A vouch sets the interval to the vouched distance +- delta and the lead's speed to its estimate
+- the speed error. Each step after, the interval's near end moves as the target braking at a_max
would (it cannot be nearer) and its far end as the target pulling away at its hardest (it cannot
be farther), both less the car's own travel (the encoder's, with its error). The near end is the
worst case the safe controller drives on; the far end says how far a witness may read and still be
the same target (the continuity check); the reach is the far end of a target that kept its vouched
speed (no faster): where a target the car lost for a moment may be re-acquired, and only while its
speed is measured (``speed_measured``: the car's own range rate and odometry, or the following
stage's confirmed estimate; an unmeasured one is taken as anywhere from standing to the top
speed, and its reach is the vouch module's to bound). A vouch narrows
the far end (never widens it: a chain of readings cannot walk the bounds away). The interval is
never dropped by time: a target tracked in the lane stays there until the lane is seen clear
(:mod:`.clear`).
"""

from __future__ import annotations

import math

from racf.experiments.car.supervisor.envelope import Envelope

__all__ = ["CarriedTarget"]


class CarriedTarget:
    """The target's camera distance bounds (``near_m``, ``far_m``) and its speed bounds, carried at
    the worst case between vouches."""

    def __init__(self, envelope: Envelope) -> None:
        self.env = envelope
        self.reset()

    def reset(self) -> None:
        self.near_m = self.far_m = self.reach_m = math.nan
        self.slow_mps = 0.0
        self.fast_mps = self._vouched_fast = 0.0
        self.unvouched_s = 0.0
        self.speed_measured = False

    @property
    def held(self) -> bool:
        """Whether a target is being carried (vouched at least once and not seen gone)."""
        return math.isfinite(self.near_m)

    def vouch(self, distance_m: float, lead_mps: float, lead_known: bool) -> None:
        """A vouched distance (m) and the lead's estimated speed (m/s; ``lead_known``: the estimate is
        measured, else the lead may be anywhere from standing to its top speed)."""
        e = self.env
        held = self.held
        far = distance_m + e.delta_m
        self.near_m = distance_m - e.delta_m
        self.far_m = min(self.far_m, far) if self.held and distance_m <= self.far_m else far
        self.reach_m = min(self.reach_m, far) if self.held and distance_m <= self.reach_m else far
        if lead_known:
            self.slow_mps = max(lead_mps - e.lead_speed_error_mps, 0.0)
            self.fast_mps = min(lead_mps + e.lead_speed_error_mps, e.target_max_mps)
            self._vouched_fast = self.fast_mps
        elif not held:  # a first sight of unknown speed: anywhere from standing to the top speed
            self.slow_mps, self.fast_mps = 0.0, e.target_max_mps
            self._vouched_fast = self.fast_mps
        # else: a speed the car has lost (a jump restarts its estimate) keeps the bounds carried so far, and
        # the reach its last measured speed (not the far end's, grown at the hardest acceleration since)
        self.speed_measured = lead_known or self.speed_measured  # (nothing held: reset, nothing measured)
        self.unvouched_s = 0.0

    def predict(self, ego_mps: float, dt: float) -> None:
        """Moves the bounds on by one step: the car travelled at ``ego_mps`` (its encoder) for ``dt``."""
        if not self.held:
            return
        e = self.env
        self.unvouched_s += dt
        travel = max(ego_mps, 0.0) * dt
        # The target brakes at a_max (near end) or pulls away at its hardest (far end).
        a = e.target_decel_mps2
        slow = max(self.slow_mps - a * dt, 0.0)
        # Exactly how far it goes braking at a_max (it may stop within the step); at most the far end's speed.
        near_travel = self.slow_mps * dt - 0.5 * a * dt ** 2 if slow > 0 else self.slow_mps ** 2 / (2 * a)
        fast = min(self.fast_mps + e.target_accel_mps2 * dt, e.target_max_mps)
        self.near_m += near_travel - travel * (1.0 + e.odometry_error)
        self.far_m += fast * dt - travel * (1.0 - e.odometry_error)
        self.reach_m += self._vouched_fast * dt - travel * (1.0 - e.odometry_error)
        self.slow_mps, self.fast_mps = slow, fast

    def holds(self, distance_m: float, tolerance_m: float) -> bool:
        """Whether a reading could be the carried target: within the bounds, give or take ``tolerance_m``."""
        return self.held and self.near_m - tolerance_m <= distance_m <= self.far_m + tolerance_m
