"""Stop-sign braking: confirm a track, trigger from the distance, brake, dwell, go on.

The controller sees, per control step, whether the detector fired, the distance a
pluggable estimator gives (raw depth, ODCA, a baseline; NaN when it has none) and the
car's speed. Its output is a speed cap for the lane follower.

- Track: confirmed after ``confirm_frames`` consecutive detections (the paper's
  accumulated detections). A confirmed track survives a missed detection while the
  estimator still gives a finite distance (raw depth does not without a detection; a
  repairing estimator does) and the map says the target should be in the camera's view,
  for at most ``track_timeout_s``. A miss with the target outside the view (it went round
  a bend, or the car passed it) is no attack: the track is dropped, so a repaired distance
  is never acted on for a target the camera cannot see.
- Trigger: on a confirmed track, brake once the distance left to the stop point (the
  stop line less ``target_gap_m``) is within the larger of the stopping distance
  v^2 / (2 a) (plus the distance covered during ``reaction_s``) and ``min_trigger_m``.
  The floor starts slow approaches early enough: signs beside the line leave the
  camera's view in the last ~0.6 m, before a 1 m/s car would need to brake. It is a
  distance, not a time, because distances measured on a curve (camera depth, a straight
  line) fall short of the distance along the curved lane.
- Braking: the remaining distance is dead-reckoned from the measured speed (wheel
  odometry) and the cap follows v = sqrt(2 a' d_remaining) with the constant deceleration
  a' = v^2 / (2 d_remaining) fixed at the trigger; a late trigger therefore brakes harder.
  The speed it plans and dead-reckons on is a bound on the body's (``SpeedBound``), not the
  encoder's reading: a hard brake just before the trigger (another stage's) locks the wheels,
  and a' planned on a locked wheel's 0.13 m/s with the body at 1.16 m/s made the car creep to
  the stop point for 4 s (the stop rule's rest clause broken, ``falsify-guarantee-sign``).
- Stopped (speed < ``stopped_mps``) -> dwell for ``dwell_s`` -> done (cap lifted; the
  sign is served and ignored from then on).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from racf.controllers.speed import SpeedBound

__all__ = ["BrakingConfig", "Phase", "BrakeDecision", "StopSignBraker"]


class Phase(str, Enum):
    CRUISE = "cruise"
    BRAKING = "braking"
    STOPPED = "stopped"
    DONE = "done"


@dataclass(frozen=True)
class BrakingConfig:
    """Parameters of the braking controller.

    Attributes:
        confirm_frames: consecutive detections that confirm a stop-sign track.
        decel_mps2: planning deceleration: the trigger fires no later than this needs
            (the tyres give ~7 m/s^2).
        min_trigger_m: the trigger fires no later than this far before the stop point.
        target_gap_m: where to come to rest, metres before the stop line (the success
            band is 0 to 0.60 m).
        reaction_s: allowance for the speed loop's and the motors' lag, seconds.
        max_distance_m: distance estimates beyond this are not acted on.
        track_timeout_s: longest a confirmed track lives without a detection.
        stopped_mps: speed below which the car is at rest (the protocol's 0.05 m/s).
        dwell_s: time at rest before going on.
    """

    confirm_frames: int = 3
    decel_mps2: float = 3.0
    min_trigger_m: float = 0.45
    target_gap_m: float = 0.30
    reaction_s: float = 0.06
    max_distance_m: float = 3.5
    track_timeout_s: float = 3.5
    stopped_mps: float = 0.05
    dwell_s: float = 1.0

    def __post_init__(self) -> None:
        if not (isinstance(self.confirm_frames, int) and 1 <= self.confirm_frames <= 100):
            raise ValueError(f"confirm_frames must be an int in [1, 100], got {self.confirm_frames!r}")
        for name, lo, hi in (("decel_mps2", 0.1, 10.0), ("min_trigger_m", 0.0, 5.0), ("target_gap_m", 0.0, 2.0), ("reaction_s", 0.0, 1.0),
                             ("max_distance_m", 0.2, 20.0), ("track_timeout_s", 0.0, 60.0),
                             ("stopped_mps", 0.001, 0.5), ("dwell_s", 0.0, 60.0)):
            value = getattr(self, name)
            if not lo <= value <= hi:
                raise ValueError(f"{name} must be in [{lo}, {hi}], got {value!r}")


@dataclass(frozen=True)
class BrakeDecision:
    """One step's output.

    Attributes:
        speed_cap_mps: upper bound on the speed reference (inf = no constraint).
        brake: whether the braking command is on (from the trigger until done).
        phase: the controller's phase after this step.
        confirmed: whether a stop-sign track is confirmed.
        distance_to_line_m: the estimate the controller acts on (NaN if none).
    """

    speed_cap_mps: float
    brake: bool
    phase: Phase
    confirmed: bool
    distance_to_line_m: float


class StopSignBraker:
    """The braking state machine for one stop-sign approach.

    Args:
        config: parameters.
        sign_depth_at_line_m: the sign's camera depth when the front bumper is on the stop
            line (map knowledge: camera-to-bumper offset plus how far past the line the sign
            stands), so that distance to the line = estimate - this.
    """

    def __init__(self, config: BrakingConfig | None = None, sign_depth_at_line_m: float = 0.12) -> None:
        if not -1.0 <= sign_depth_at_line_m <= 2.0:
            raise ValueError(f"sign_depth_at_line_m must be in [-1, 2] m, got {sign_depth_at_line_m}")
        self.config = config or BrakingConfig()
        self.sign_depth_at_line_m = float(sign_depth_at_line_m)
        self.reset()

    def reset(self) -> None:
        self.phase = Phase.CRUISE
        self._streak = 0
        self._confirmed = False
        self._since_detection_s = 0.0
        self._remaining_m = math.inf
        self._profile_decel = self.config.decel_mps2
        self._dwell_s = 0.0
        self._speed = SpeedBound(error=0.0)

    def step(self, detected: bool, distance_m: float, speed_mps: float, dt: float,
             expected_in_view: bool = True) -> BrakeDecision:
        """Advance one control step.

        Args:
            detected: whether the detector reported a stop sign this step.
            distance_m: the estimator's camera-to-sign distance (NaN when none).
            speed_mps: measured speed.
            dt: control period, seconds.
            expected_in_view: whether the map puts the target inside the camera's view.
        """
        if not dt > 0:
            raise ValueError(f"dt must be > 0 s, got {dt}")
        c = self.config
        distance_m = float(distance_m)
        has_distance = math.isfinite(distance_m) and 0.0 < distance_m <= c.max_distance_m
        to_line = distance_m - self.sign_depth_at_line_m if has_distance else math.nan
        self._update_track(bool(detected), has_distance and bool(expected_in_view), dt)
        speed = self._speed.step(float(speed_mps), dt)

        if self.phase is Phase.CRUISE and self._confirmed and has_distance:
            remaining = to_line - c.target_gap_m
            if remaining <= max(speed * speed / (2 * c.decel_mps2) + speed * c.reaction_s, c.min_trigger_m):
                self.phase, self._remaining_m = Phase.BRAKING, remaining
                # Brake from now on at the constant deceleration that ends at the stop point.
                self._profile_decel = speed * speed / (2 * remaining) if remaining > 0 else math.inf
        elif self.phase is Phase.BRAKING:
            self._remaining_m -= speed * dt
        if self.phase is Phase.BRAKING and speed < c.stopped_mps:
            self.phase, self._dwell_s = Phase.STOPPED, 0.0
        elif self.phase is Phase.STOPPED:
            self._dwell_s += dt
            if self._dwell_s >= c.dwell_s:
                self.phase = Phase.DONE

        if self.phase is Phase.BRAKING:
            cap = math.sqrt(2 * self._profile_decel * self._remaining_m) if self._remaining_m > 0 else 0.0
        elif self.phase is Phase.STOPPED:
            cap = 0.0
        else:
            cap = math.inf
        return BrakeDecision(cap, self.phase in (Phase.BRAKING, Phase.STOPPED), self.phase, self._confirmed, to_line)

    def _update_track(self, detected: bool, has_distance: bool, dt: float) -> None:
        c = self.config
        self._streak = self._streak + 1 if detected else 0
        self._since_detection_s = 0.0 if detected else self._since_detection_s + dt
        if self._streak >= c.confirm_frames:
            self._confirmed = True
        elif self._confirmed and not detected and (not has_distance or self._since_detection_s > c.track_timeout_s):
            self._confirmed = False
