"""Where an episode puts the car and what it meets: the route, its targets, the start and the
cruise speed, from the env's reset options and the map. Pure: nothing here knows MuJoCo.

The env calls :func:`plan_route` at each reset (its seeded generator fills in what the options
leave open), and the car's briefing is made from the same call before the episode
(``racf.experiments.episode.plan``): both read one source, and nothing is read back out of the
env. :func:`current_slot` is the one rule for which target is being served, applied by the
env to the true pose (for the referee) and by the car to its own estimate.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np

from racf.sim.world.drives import RouteTarget, start_pose, targets_on_path
from racf.sim.world.obstacles import Obstacle, obstacles
from racf.sim.world.road_graph import Path, qcar2_road_graph
from racf.sim.world.stop_signs import SignGeometry, stop_signs

__all__ = ["RoutePlan", "plan_route", "current_slot", "longest_run_up_m", "PASS_LINE_M", "DRIVE_OPTIONS"]

#: On a drive, the next target becomes current once the front bumper is this far past the
#: current one's stop line (the car has served it and driven on), m.
PASS_LINE_M = 0.3
#: The reset options that only a drive (``options["route"]``) takes.
DRIVE_OPTIONS = ("route", "start_s_m", "lateral_offset_m", "heading_error_rad", "crate")


@dataclass(frozen=True)
class RoutePlan:
    """An episode's route.

    Attributes:
        path: the lane-centre path the car follows.
        targets: the targets it meets, in order.
        crate: the crate placed on the route (None: none).
        start_s: where the body origin starts along ``path``, m.
        start_pose: (x, y, yaw) of the start, map frame.
        cruise_mps: the cruise speed, m/s.
    """

    path: Path
    targets: tuple[RouteTarget, ...]
    crate: int | None
    start_s: float
    start_pose: np.ndarray
    cruise_mps: float


def plan_route(options: dict[str, Any], *, sign_geometry: SignGeometry, bumper_ahead_m: float, max_speed_mps: float,
               cruise_speeds_mps: tuple[float, ...], rng: np.random.Generator) -> RoutePlan:
    """The route the reset ``options`` ask for: an approach to a stop sign or a crate, or a drive
    (``options["route"]``). ``rng`` draws what they leave open (the target, the cruise speed);
    it draws them even when the options give them, so that the draws after a reset are the
    same whatever the options say. ValueError names a bad option and what is allowed."""
    if "route" in options:
        return _drive(options, sign_geometry, lambda: _cruise(options, max_speed_mps, cruise_speeds_mps, rng))
    return _approach(options, sign_geometry, bumper_ahead_m,
                     lambda: _cruise(options, max_speed_mps, cruise_speeds_mps, rng), rng)


def current_slot(targets: tuple[RouteTarget, ...], slot: int, bumper_s: float) -> int:
    """The target being served, given the last one (``slot``) and where the front bumper is along
    the route (``bumper_s``, m): the next becomes current once the bumper is ``PASS_LINE_M``
    past the current one's stop line."""
    while slot + 1 < len(targets) and bumper_s - targets[slot].stop_s > PASS_LINE_M:
        slot += 1
    return slot


def _longest(target, bumper_ahead_m: float) -> float:
    return target.stop_s - target.earliest_start_s - bumper_ahead_m


def longest_run_up_m(target: str, index: int, geometry: SignGeometry, bumper_ahead_m: float) -> float:
    """The longest run-up an approach to this ``sign`` or ``obstacle`` allows, m (its lane's length)."""
    targets = obstacles() if target == "obstacle" else stop_signs(geometry)
    return _longest(targets[index], bumper_ahead_m)


def _approach(options: dict[str, Any], geometry: SignGeometry, bumper_ahead_m: float, cruise,
              rng: np.random.Generator) -> RoutePlan:
    extra = sorted(set(options) & set(DRIVE_OPTIONS))
    if extra:
        raise ValueError(f"reset option(s) {extra} need options['route'] (a drive)")
    if "sign" in options and "obstacle" in options:
        raise ValueError("pass options['sign'] (a stop sign) or options['obstacle'] (a crate), not both")
    key, targets = ("obstacle", obstacles()) if "obstacle" in options else ("sign", stop_signs(geometry))
    drawn = int(rng.integers(len(targets)))
    index = options.get(key, drawn)
    if not _is_int(index) or int(index) not in range(len(targets)):
        raise ValueError(f"options[{key!r}] must be an int in 0..{len(targets) - 1}, got {index!r}")
    sign = targets[int(index)]
    speed = cruise()
    longest = _longest(sign, bumper_ahead_m)
    run_up = options.get("run_up_m", min(3.0, longest))
    if not (_is_real(run_up) and 0.3 <= run_up <= longest + 1e-9):
        raise ValueError(f"options['run_up_m'] for sign {sign.index} must be in [0.3, {longest:.2f}] m, got {run_up!r}")
    s_target, _ = sign.path.project(np.asarray(sign.position), s_hint=sign.stop_s, window_m=0.6)
    start_s = sign.stop_s - run_up - bumper_ahead_m
    crate = sign.index if isinstance(sign, Obstacle) else None
    return RoutePlan(sign.path, (RouteTarget(sign, sign.stop_s, s_target),), crate, start_s,
                     np.asarray(sign.path.pose_at(start_s)), speed)


def _drive(options: dict[str, Any], geometry: SignGeometry, cruise) -> RoutePlan:
    clash = sorted(set(options) & {"sign", "obstacle", "run_up_m"})
    if clash:
        raise ValueError(f"reset option(s) {clash} do not combine with options['route'] (a drive)")
    route = options["route"]
    if isinstance(route, (str, bytes)) or not all(_is_int(n) for n in route):
        raise ValueError(f"options['route'] must be a sequence of road-graph node ids, got {route!r}")
    path = qcar2_road_graph().route_path([int(n) for n in route])  # ValueError names a bad edge
    crate = options.get("crate")
    if crate is not None and (not _is_int(crate) or int(crate) not in range(len(obstacles()))):
        raise ValueError(f"options['crate'] must be None or an int in 0..{len(obstacles()) - 1}, got {crate!r}")
    start_s = options.get("start_s_m", 0.0)
    if not (_is_real(start_s) and 0.0 <= start_s < path.length - 0.5):
        raise ValueError(f"options['start_s_m'] must be in [0, {path.length - 0.5:.2f}) m, got {start_s!r}")
    lateral = options.get("lateral_offset_m", 0.0)
    if not (_is_real(lateral) and abs(lateral) <= 0.1):
        raise ValueError(f"options['lateral_offset_m'] must be in [-0.1, 0.1] m, got {lateral!r}")
    heading_err = options.get("heading_error_rad", 0.0)
    if not (_is_real(heading_err) and abs(heading_err) <= 0.5):
        raise ValueError(f"options['heading_error_rad'] must be in [-0.5, 0.5] rad, got {heading_err!r}")
    targets = targets_on_path(path, crate, float(start_s), geometry=geometry)
    if not targets:
        raise ValueError(f"route {list(route)} meets no target after start_s_m={start_s}: no stop sign "
                         "faces its lanes (and no crate is placed on it)")
    speed = cruise()
    return RoutePlan(path, targets, crate, float(start_s),
                     np.asarray(start_pose(path, float(start_s), float(lateral), float(heading_err))), speed)


def _cruise(options: dict[str, Any], max_speed_mps: float, speeds: tuple[float, ...], rng: np.random.Generator) -> float:
    drawn = float(rng.choice(speeds))
    speed = options.get("cruise_speed", drawn)
    if not (_is_real(speed) and 0.0 <= speed <= max_speed_mps):
        raise ValueError(f"options['cruise_speed'] must be in [0, {max_speed_mps}] m/s, got {speed!r}")
    return float(speed)


def _is_int(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _is_real(value: Any) -> bool:
    """A finite real number (NaN compares false with every range check, reject it here)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and value == value
