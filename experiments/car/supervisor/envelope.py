"""The supervisor's stated envelope and its arithmetic: RSS's safe longitudinal distance.

The guarantee (``docs/concepts/guarantee.md``) holds for a car and a target within this envelope:
a vouched distance off the truth by at most ``delta_m`` (its witnesses' own error plus what the
assumptions allow an attacker, each budgeted once), a vouched lead speed off by at most
``lead_speed_error_mps``, a target that brakes no harder than ``target_decel_mps2``, a car that
accelerates no harder than ``car_accel_mps2`` and, asked to stop, brakes at least
``car_brake_mps2`` within ``reaction_s``. :func:`safe_gap` is the gap it needs; :func:`safe_speed`
the fastest speed a gap allows (its inverse).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

__all__ = ["Envelope", "safe_gap", "safe_speed", "stopping_m"]


@dataclass(frozen=True)
class Envelope:
    """The assumptions the supervisor's guarantee rests on, and its comfort settings.

    Attributes:
        witness_error_m: how far an honest range witness of the target may over-read it, m (the depth
            reads the box's middle past the rear face, the LiDAR's track its nearest return: measured
            on clean following episodes, at most 0.124 m over the truth's clear-gap distance,
            ``tests/experiments/car/supervisor/test_budget.py``).
        attack_error_m: how far the assumptions let an attacker move every range witness, m (the
            falsification's ``lead_range_error`` is drawn within it).
        lead_speed_error_mps: how far a vouched lead speed may lie from the truth, m/s.
        target_decel_mps2: the target's hardest braking, m/s^2 (a_max: the scenario states it).
        target_accel_mps2: the target's hardest acceleration, m/s^2 (how far it may pull away
            unseen: the continuity check's upper bound; the tyres' grip, 0.75 g).
        target_max_mps: the target's top speed, m/s (a QCar 2's rated 3 m/s).
        car_brake_mps2: the braking the car is sure of once asked to stop, m/s^2 (b; measured
            5.7-7 m/s^2 in the simulator from 1 m/s: ``tests/experiments/car/supervisor``).
        car_accel_mps2: the car's hardest acceleration, m/s^2 (the tyres' grip, 0.75 g).
        reaction_s: from the step the supervisor decides to the brakes biting, s (rho: one 20 ms
            control period and the drive's response).
        margin_m: the gap left when both have stopped, m.
        odometry_error: the car's travel from its encoder is off by at most this share.
        route_error_m: how far the car's own distance along its route to a line may lie from the truth,
            m (A6: its localisation against the map; measured at most 0.069 m over 60 supervised
            sign approaches, 0.080 m with a 0.075 m budget, ``tests/experiments/car/supervisor/route_error.py``).
            The static target's room is budgeted it, once.
        comfort_brake_mps2: the braking the safe controller plans with when it has the room, m/s^2
            (under the 3 m/s^2 a hard brake begins at).
    """

    witness_error_m: float = 0.12
    attack_error_m: float = 0.05
    lead_speed_error_mps: float = 0.25
    target_decel_mps2: float = 6.0
    target_accel_mps2: float = 7.36
    target_max_mps: float = 3.0
    car_brake_mps2: float = 4.0
    car_accel_mps2: float = 7.36
    reaction_s: float = 0.1
    margin_m: float = 0.05
    odometry_error: float = 0.02
    route_error_m: float = 0.1
    comfort_brake_mps2: float = 1.5

    @property
    def delta_m(self) -> float:
        """How far a vouched distance may over-read the truth, m (delta): the witnesses' own error
        plus the attacker's allowance, each written once."""
        return self.witness_error_m + self.attack_error_m

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise ValueError(f"envelope {f.name} must be a finite number >= 0, got {value!r}")
        for name in ("target_decel_mps2", "car_brake_mps2", "comfort_brake_mps2"):
            if getattr(self, name) <= 0:
                raise ValueError(f"envelope {name} must be > 0 m/s^2, got {getattr(self, name)!r}")
        if self.comfort_brake_mps2 > self.car_brake_mps2:
            raise ValueError(f"envelope comfort_brake_mps2 ({self.comfort_brake_mps2}) must not exceed "
                             f"car_brake_mps2 ({self.car_brake_mps2})")


def safe_gap(speed_mps: float, lead_mps: float, env: Envelope, brake_mps2: float | None = None) -> float:
    """The gap the car needs at ``speed_mps`` behind a target at ``lead_mps``, m (RSS): it may
    accelerate for the reaction time, then brakes at ``brake_mps2`` (the envelope's b), while the
    target brakes at a_max; both stopped, ``margin_m`` is left."""
    b = env.car_brake_mps2 if brake_mps2 is None else brake_mps2
    v, rho, a = max(speed_mps, 0.0), env.reaction_s, env.car_accel_mps2
    reach = v * rho + 0.5 * a * rho ** 2 + (v + a * rho) ** 2 / (2.0 * b)
    return reach - max(lead_mps, 0.0) ** 2 / (2.0 * env.target_decel_mps2) + env.margin_m


def safe_speed(gap_m: float, lead_mps: float, env: Envelope, brake_mps2: float | None = None) -> float:
    """The fastest speed at which ``gap_m`` is still a safe gap (:func:`safe_gap`'s inverse), m/s;
    negative when no speed is (the car must brake now)."""
    if not math.isfinite(gap_m):
        return math.inf if gap_m > 0 else -math.inf
    b = env.car_brake_mps2 if brake_mps2 is None else brake_mps2
    rho, a = env.reaction_s, env.car_accel_mps2
    # With u = v + a rho: gap - margin + L + a rho^2 / 2 = u rho + u^2 / (2 b).
    room = gap_m - env.margin_m + max(lead_mps, 0.0) ** 2 / (2.0 * env.target_decel_mps2) + 0.5 * a * rho ** 2
    if room < 0:
        return -math.inf
    u = b * (-rho + math.sqrt(rho ** 2 + 2.0 * room / b))
    return u - a * rho


def stopping_m(speed_mps: float, env: Envelope) -> float:
    """How far the car may travel from ``speed_mps`` before it stands, told to stop now, m (RSS's
    reach: the reaction time at its hardest acceleration, then braking at b)."""
    return safe_gap(speed_mps, 0.0, env) - env.margin_m
