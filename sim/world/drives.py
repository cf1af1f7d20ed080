"""Drives: continuous routes through the road graph, and the targets met along them.

A drive is a route (road-graph nodes), the lane-centre path along it, where on that path
the car starts, and the targets it meets in order: every stop sign whose stop line the
path crosses in the sign's own direction of travel, and at most one crate, which ends
the drive. ``draw_drive`` draws one from a seeded generator (start node, run-up, lateral
offset, heading error, cruise speed); the env places the car with ``reset(options=...)``.
Pure numpy: nothing here knows MuJoCo.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.sim.world.obstacles import Obstacle, obstacles
from racf.sim.world.road_graph import Path, qcar2_road_graph
from racf.sim.world.stop_signs import PLATE_IN_SCAN, SignGeometry, StopSign, stop_signs

__all__ = ["RouteTarget", "DriveSpec", "targets_on_path", "draw_drive", "start_pose", "estimate_duration_s", "NOMINAL_SPEEDS_MPS",
           "MIN_TARGET_AHEAD_M"]

#: The nominal cruise speeds a drive draws from (each then scaled by U(0.9, 1.1)).
NOMINAL_SPEEDS_MPS = (1.0, 1.5, 2.0)
#: A target whose stop line is closer than this to the start is not one the car can serve.
MIN_TARGET_AHEAD_M = 2.0
#: How close to a stop line (laterally) and how aligned (cos of the heading difference)
#: the path must pass for the target to count as met.
_ON_LINE_M = 0.06
_ALIGNED_COS = 0.9


@dataclass(frozen=True)
class RouteTarget:
    """One target on a drive's path.

    Attributes:
        target: the stop sign or crate.
        stop_s: arclength of its stop line along the drive's path, m.
        target_s: arclength where the path passes the target (sign pole / crate face), m.
        mapped: whether the car's map lists it (False: a temporary sign, or a picture of one, the
            car must find for itself; its position fields are then the referee's, never the car's).
    """

    target: StopSign | Obstacle
    stop_s: float
    target_s: float
    mapped: bool = True

    @property
    def kind(self) -> str:
        """``"sign"`` or ``"obstacle"``."""
        return "obstacle" if isinstance(self.target, Obstacle) else "sign"

    @property
    def name(self) -> str:
        """``sign0``..``sign3`` or ``obstacle0``..``obstacle1``."""
        return f"{self.kind}{self.target.index}"


@dataclass(frozen=True)
class DriveSpec:
    """What a drive is, as drawn from its seed (all the env's ``reset`` options).

    Attributes:
        route: road-graph nodes.
        start_s_m: where on the path the car's body origin starts (the run-up along the first edge), m.
        lateral_offset_m: start offset left of the lane centre, m.
        heading_error_rad: start heading minus the lane's, rad.
        cruise_speed_mps: cruise speed.
        crate: index of the crate that ends the drive, or None.
    """

    route: tuple[int, ...]
    start_s_m: float
    lateral_offset_m: float
    heading_error_rad: float
    cruise_speed_mps: float
    crate: int | None = None

    def reset_options(self) -> dict:
        """The env's ``reset(options=...)`` for this drive."""
        return {"route": self.route, "start_s_m": self.start_s_m, "lateral_offset_m": self.lateral_offset_m,
                "heading_error_rad": self.heading_error_rad, "cruise_speed": self.cruise_speed_mps,
                "crate": self.crate}


def _crossings(path: Path, point: np.ndarray, heading: float) -> list[float]:
    """Arclengths where ``path`` passes within ``_ON_LINE_M`` of ``point`` heading along ``heading``."""
    near = np.linalg.norm(path.points - point, axis=1) < 0.25
    aligned = np.cos(path.headings - heading) > _ALIGNED_COS
    idx = np.flatnonzero(near & aligned)
    out: list[float] = []
    if idx.size == 0:
        return out
    # One crossing per run of consecutive points (a route may pass the same place twice).
    for run in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1):
        s_mid = float(path.arclength[run[len(run) // 2]])
        s, lateral = path.project(point, s_hint=s_mid, window_m=0.3)
        if abs(lateral) < _ON_LINE_M:
            out.append(s)
    return out


def targets_on_path(path: Path, crate: int | None = None, start_s: float = 0.0,
                    geometry: SignGeometry = PLATE_IN_SCAN) -> tuple[RouteTarget, ...]:
    """The stop signs (and the crate, if placed) the path meets after ``start_s``, in order.

    The signs are ``stop_signs(geometry)``: which signs are met and where does not depend on
    the geometry, only the ``StopSign`` objects (their ``centre``) do.

    A stop sign counts where the path crosses its stop line in the direction of the sign's
    own approach; a crate where the path reaches its virtual stop line. Targets whose stop
    line lies less than ``MIN_TARGET_AHEAD_M`` past ``start_s`` are left out (no car could
    serve them). Nothing after the crate counts: the crate ends the drive.

    Raises:
        ValueError: the crate stands on the path closer than that ahead of the start, or
            the path runs into it without crossing its stop line first.
    """
    found: list[RouteTarget] = []
    candidates: list[StopSign | Obstacle] = list(stop_signs(geometry))
    if crate is not None:
        candidates.append(obstacles()[crate])
    for target in candidates:
        line = np.asarray(target.stop_line, float)
        heading = target.path.pose_at(target.stop_s)[2]
        for stop_s in _crossings(path, line, heading):
            if stop_s < start_s + MIN_TARGET_AHEAD_M:
                if isinstance(target, Obstacle) and stop_s > start_s - 0.5:
                    raise ValueError(f"crate {target.index} stands {stop_s - start_s:.2f} m ahead of the start; "
                                     f"a crate must be >= {MIN_TARGET_AHEAD_M} m ahead (or behind the car)")
                continue
            if isinstance(target, Obstacle):
                target_s = stop_s + _standoff(target)
            else:
                target_s, _ = path.project(np.asarray(target.position), s_hint=stop_s, window_m=0.6)
            found.append(RouteTarget(target, float(stop_s), float(target_s)))
    found.sort(key=lambda t: t.stop_s)
    for i, t in enumerate(found):
        if t.kind == "obstacle":
            found = found[:i + 1]
            break
    if crate is not None:
        _check_crate_clear(path, obstacles()[crate], start_s, found[-1].stop_s if found and
                           found[-1].kind == "obstacle" else path.length)
    return tuple(found)


#: The car's path must keep this far from a placed crate's centre (half the car's width,
#: half the crate's width across the lane and a margin; the opposite lane, 0.27 m away,
#: passes), except on the approach that ends at it.
_CRATE_CLEARANCE_M = 0.2


def _check_crate_clear(path: Path, crate: Obstacle, start_s: float, end_s: float) -> None:
    """Raises ValueError when the path between start_s and end_s runs into the crate (e.g. by
    merging onto its lane past its stop line)."""
    part = (path.arclength >= start_s - 0.3) & (path.arclength <= end_s)
    gap = np.linalg.norm(path.points[part] - np.asarray(crate.body_centre), axis=1)
    if gap.size and gap.min() < _CRATE_CLEARANCE_M:
        raise ValueError(f"the route runs into crate {crate.index} (within {gap.min():.2f} m of it) "
                         "without meeting its stop line first")


def _standoff(crate: Obstacle) -> float:
    """Stop line to the crate's near face, along the lane, m."""
    s_face, _ = crate.path.project(np.asarray(crate.position), s_hint=crate.stop_s, window_m=1.0)
    return s_face - crate.stop_s


def draw_drive(rng: np.random.Generator, min_duration_s: float = 20.0, max_duration_s: float = 60.0,
               crate_share: float = 0.3, min_targets: int = 2, nominal_speed_mps: float | None = None,
               max_tries: int = 200) -> DriveSpec:
    """Draws a drive: a random walk through the road graph that meets ``min_targets`` or more.

    The seed draws the start node, the run-up (start point along the first edge), the
    lateral offset (+-3 cm), the heading error (+-5 deg), the cruise speed (a nominal
    speed of ``NOMINAL_SPEEDS_MPS`` x U(0.9, 1.1)), a duration the walk is grown to
    (``estimate_duration_s``; drawn within the limits less a margin for the estimate's
    error), and whether the drive ends at a crate (the walk then takes the shortest way
    onto the crate's lane). Walks with too few targets, or that would run into the crate,
    are drawn again from the same generator. ``nominal_speed_mps`` fixes the nominal speed
    (a collection balances them); the +-10 % draw still applies.
    """
    if not 0 < min_duration_s <= max_duration_s:
        raise ValueError(f"need 0 < min_duration_s <= max_duration_s, got {min_duration_s}, {max_duration_s}")
    if not 0.0 <= crate_share <= 1.0:
        raise ValueError(f"crate_share must be in [0, 1], got {crate_share}")
    if min_targets < 1:
        raise ValueError(f"min_targets must be >= 1, got {min_targets}")
    graph = qcar2_road_graph()
    nodes = sorted(graph.nodes)
    for _ in range(max_tries):
        start = int(rng.choice(nodes))
        nominal = float(rng.choice(NOMINAL_SPEEDS_MPS)) if nominal_speed_mps is None else nominal_speed_mps
        speed = nominal * float(rng.uniform(0.9, 1.1))
        lateral = float(rng.uniform(-0.03, 0.03))
        heading_err = float(np.radians(rng.uniform(-5.0, 5.0)))
        lo, hi = _margin(min_duration_s, max_duration_s)
        duration = float(rng.uniform(lo, hi))
        crate = int(rng.integers(len(obstacles()))) if rng.random() < crate_share else None
        route = [start]
        route.append(int(rng.choice(graph.successors(start))))
        start_s = float(rng.uniform(0.0, 0.6) * graph.paths[(route[0], route[1])].length)
        targets, est_s = _grow(rng, route, start_s, speed, duration, crate)
        if len(targets) < min_targets or (crate is not None and targets[-1].kind != "obstacle"):
            continue
        if not lo <= est_s <= hi:
            continue
        if crate is not None:
            # The route ends at the crate: drop the nodes beyond the edge that holds it.
            route = _trim_after(route, targets[-1].stop_s)
        return DriveSpec(tuple(route), start_s, lateral, heading_err, speed, crate)
    raise RuntimeError(f"no drive with >= {min_targets} targets in {max_tries} draws; loosen the limits")


#: The duration estimate's error on 39 recorded drives was within 2.1 s (std 0.7 s).
_ESTIMATE_ERROR_S = 2.5
#: Fitted on those drives: a stop costs 1.5 s beyond driving its distance (braking, the
#: 1 s dwell, pulling away), speed changes stretch the driving time by 5 %, and a drive
#: ends 1.5 s after its last stop line's time (the car stops before it and dwells).
_STOP_COST_S = 1.5
_DRIVE_STRETCH = 1.05
_END_OFFSET_S = -1.5
#: Lateral acceleration of the route follower's curve speed limit, m/s^2.
_CURVE_ACCEL_MPS2 = 2.0


def _margin(lo: float, hi: float) -> tuple[float, float]:
    """The estimate's window inside [lo, hi], narrowed by the estimate's error where there is room."""
    pad = min(_ESTIMATE_ERROR_S, (hi - lo) / 4)
    return lo + pad, hi - pad


def estimate_duration_s(path: Path, start_s: float, targets: tuple[RouteTarget, ...], speed_mps: float) -> float:
    """How long a drive takes to its last target, s: the path at the cruise speed capped on
    curves (as the route follower's limit), plus a fixed cost per stop."""
    if not targets:
        return 0.0
    s, k = path.arclength, np.abs(path.curvature)
    part = (s >= start_s) & (s <= targets[-1].stop_s)
    v = np.minimum(speed_mps, np.sqrt(_CURVE_ACCEL_MPS2 / np.maximum(k[part], 1e-9)))
    ds = np.diff(s[part], append=s[part][-1]) if part.any() else np.zeros(0)
    return float(_DRIVE_STRETCH * np.sum(ds / v) + _STOP_COST_S * len(targets) + _END_OFFSET_S)


def _grow(rng: np.random.Generator, route: list[int], start_s: float, speed: float, duration: float,
          crate: int | None) -> tuple[tuple[RouteTarget, ...], float]:
    """Extends ``route`` in place by random successors until the drive lasts ``duration``;
    with a crate, then by the shortest way onto the crate's lane and up to it. Returns the
    targets and the estimated duration (no targets when the route runs into the crate)."""
    graph = qcar2_road_graph()
    # A crate's approach from its lane's first node takes about this long.
    reserve = 0.0 if crate is None else obstacles()[crate].stop_s / speed + 3.0
    while True:
        path = graph.route_path(route)
        targets = targets_on_path(path, None, start_s)
        est_s = estimate_duration_s(path, start_s, targets, speed)
        if est_s >= duration - reserve or path.length > 200.0:
            break
        route.append(int(rng.choice(graph.successors(route[-1]))))
    if crate is not None:
        lane = obstacles()[crate].route
        route += graph.shortest_route(route[-1], lane[0])[1:] + list(lane[1:])
        path = graph.route_path(route)
        try:
            targets = targets_on_path(path, crate, start_s)
        except ValueError:  # the route runs into the crate
            return (), math.inf
        est_s = estimate_duration_s(path, start_s, targets, speed)
    return targets, est_s


def _trim_after(route: list[int], s: float) -> list[int]:
    """The route up to and including the first edge that ends past arclength ``s`` (+ 0.5 m)."""
    graph = qcar2_road_graph()
    total = 0.0
    for i, (a, b) in enumerate(zip(route, route[1:])):
        total += graph.paths[(a, b)].length
        if total >= s + 0.5:
            return route[:i + 2]
    return route


def start_pose(path: Path, start_s: float, lateral_offset_m: float, heading_error_rad: float
               ) -> tuple[float, float, float]:
    """(x, y, yaw) of the car's body origin at the drive's start, map frame."""
    x, y, h = path.pose_at(start_s)
    return (x - math.sin(h) * lateral_offset_m, y + math.cos(h) * lateral_offset_m, h + heading_error_rad)
