"""Other cars on the map: where each stop sign's cross-traffic drives and when it gets there.

Each stop sign guards a place past its line where another lane meets the ego car's: the
conflict point. ``conflict_of`` finds it on the road graph: the first point of the ego car's
path past the line that another lane's centre comes within ``CONFLICT_RADIUS_M`` of (a lane
that crosses it or merges into it). Sign 0 stands at a corner that no lane crosses or joins;
its cross-traffic is the oncoming car on the neighbouring lane, met 0.6 m past the line, where a
car that ran the stop would be (``kind == "adjacent"``: a missed stop there need not be a crash).

The other cars are kinematic: each follows its lane's centre at a set speed, a pure function of
time (``TrafficCar.state_at``). Why kinematic: the scenario needs a car at the conflict point at a
planned time, to the millisecond and the same on every machine; a dynamic car would need its
own controller and wheel contacts, whose cost the real-time factor pays, to do no better at the
one thing it must do. They keep their own right of way: no stop sign faces them before the
conflict (``cross_traffic`` builds their routes around them), and one that faces them after it
stops them at its line. Nothing in them reads the ego car, its sensing or its decisions.

Pure numpy: nothing here knows MuJoCo.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from racf.sim.world.drives import targets_on_path
from racf.sim.world.manager import QCAR2_BOX_M
from racf.sim.world.road_graph import Path, qcar2_road_graph
from racf.sim.world.stop_signs import StopSign, stop_signs

__all__ = ["TrafficCar", "ConflictPoint", "conflict_of", "cross_traffic", "TRAFFIC_COLOURS", "CONFLICT_RADIUS_M",
           "MAX_TRAFFIC_CARS", "TRAFFIC_BRAKE_MPS2", "HEADWAY_S", "CAR_FOOTPRINT_M"]

#: A QCar 2's footprint, length x width, m (its MJCF: bumper to bumper, wheel to wheel), centred
#: on its body origin, which sits midway between the axles.
CAR_FOOTPRINT_M = QCAR2_BOX_M[:2]

#: Two lane centres this close meet (a QCar 2 is 0.192 m wide: two side by side touch at 0.19 m).
CONFLICT_RADIUS_M = 0.12
#: How many other cars an env can hold (the palette's size).
MAX_TRAFFIC_CARS = 4
#: Each other car's body colour (RGBA), by name; car k takes the k-th unless told otherwise.
TRAFFIC_COLOURS: dict[str, tuple[float, float, float, float]] = {
    "red": (0.78, 0.07, 0.07, 1.0),
    "blue": (0.10, 0.25, 0.75, 1.0),
    "yellow": (0.90, 0.75, 0.10, 1.0),
    "white": (0.92, 0.92, 0.92, 1.0),
}
#: How hard another car brakes for a stop line or the end of its route, m/s^2.
TRAFFIC_BRAKE_MPS2 = 2.0
#: Time between two other cars that follow one another through the conflict, s.
HEADWAY_S = 1.5
#: Each sign's cross-traffic lane, a road-graph edge (the conflict point is found on it).
_CROSS_LANES: dict[int, tuple[int, int]] = {0: (20, 22), 1: (8, 10), 2: (7, 14), 3: (7, 14)}
#: Where no lane meets the ego car's, its conflict point lies this far past the stop line, m.
_ADJACENT_PAST_M = 0.6
#: Road a car keeps at least this far past the conflict point before its route ends, m.
_CLEAR_AFTER_M = 2.0


@dataclass(frozen=True)
class ConflictPoint:
    """Where a stop sign's cross-traffic meets the ego car's path.

    Attributes:
        sign: the stop sign's index.
        xy: the point on the ego car's lane centre, map frame, m.
        ego_s: its arclength along the sign's approach path, m.
        lane: the cross-traffic's road-graph edge.
        lane_s: the arclength on that edge where it meets the point, m.
        kind: ``crossing`` (the lanes cross at an angle), ``merge`` (the lane joins the ego
            car's) or ``adjacent`` (no lane meets it: the oncoming lane passes beside it).
    """

    sign: int
    xy: tuple[float, float]
    ego_s: float
    lane: tuple[int, int]
    lane_s: float
    kind: str


@lru_cache(maxsize=8)
def conflict_of(sign: int) -> ConflictPoint:
    """The conflict point past stop sign ``sign``'s line (0..3)."""
    if not isinstance(sign, numbers.Integral) or sign not in _CROSS_LANES:
        raise ValueError(f"sign must be an int in 0..{len(_CROSS_LANES) - 1}, got {sign!r}")
    target = stop_signs()[sign]
    ego, lane_edge = target.path, _CROSS_LANES[sign]
    lane = qcar2_road_graph().paths[lane_edge]
    past = np.flatnonzero(ego.arclength >= target.stop_s)
    gaps = np.linalg.norm(ego.points[past][:, None, :] - lane.points[None, :, :], axis=2)
    nearest = gaps.argmin(axis=1)
    close = np.flatnonzero(gaps[np.arange(len(past)), nearest] < CONFLICT_RADIUS_M)
    # No lane meets it: the point a car that ran the line would have reached, beside the oncoming lane.
    i = int(close[0]) if close.size else int(np.searchsorted(ego.arclength[past], target.stop_s + _ADJACENT_PAST_M))
    j = int(nearest[i])
    angle = abs(math.remainder(float(ego.headings[past[i]] - lane.headings[j]), 2 * math.pi))
    kind = "adjacent" if not close.size else ("crossing" if angle > math.radians(30) else "merge")
    xy = ego.points[past[i]]
    return ConflictPoint(sign, (float(xy[0]), float(xy[1])), float(ego.arclength[past[i]]), lane_edge,
                         float(lane.arclength[j]), kind)


@dataclass(frozen=True)
class TrafficCar:
    """One other car: its lane-centre path and how it drives along it.

    Attributes:
        route: its road-graph nodes.
        start_s: where its body origin is at t = 0 along the route's path, m.
        speed_mps: its cruise speed.
        stop_s: where it comes to rest (a stop line that faces it, or its route's end), m.
        colour: a ``TRAFFIC_COLOURS`` name.
        depart_t_s: when it sets off from ``start_s``, s (before, it waits there at rest): where
            the road graph has less road before the conflict than the timing needs, the car
            waits at its route's start instead of starting further back.
    """

    route: tuple[int, ...]
    start_s: float
    speed_mps: float
    stop_s: float
    colour: str = "red"
    depart_t_s: float = 0.0

    def __post_init__(self) -> None:
        if self.colour not in TRAFFIC_COLOURS:
            raise ValueError(f"colour must be one of {tuple(TRAFFIC_COLOURS)}, got {self.colour!r}")
        if not (isinstance(self.speed_mps, numbers.Real) and 0.1 <= self.speed_mps <= 3.0):
            raise ValueError(f"speed_mps must be in [0.1, 3.0] m/s, got {self.speed_mps!r}")
        if not (isinstance(self.depart_t_s, numbers.Real) and 0.0 <= self.depart_t_s <= 60.0):
            raise ValueError(f"depart_t_s must be in [0, 60] s, got {self.depart_t_s!r}")
        length = self.path.length
        if not (0.0 <= self.start_s <= self.stop_s <= length + 1e-9):
            raise ValueError(f"need 0 <= start_s <= stop_s <= {length:.2f} m (the route's length), "
                             f"got start_s={self.start_s!r}, stop_s={self.stop_s!r}")

    @property
    def path(self) -> Path:
        return _route_path(self.route)

    def s_at(self, t: float) -> tuple[float, float]:
        """(arclength m, speed m/s) at time ``t`` s: cruise from ``depart_t_s``, then a constant-deceleration
        stop at ``stop_s`` (before it sets off: at ``start_s``, at rest)."""
        s, v = self._profile(np.array([float(t)]))
        return float(s[0]), float(v[0])

    def state_at(self, t: float) -> tuple[float, float, float, float]:
        """(x m, y m, yaw rad, speed m/s) in the map frame at time ``t`` s."""
        return tuple(float(v) for v in self.states(np.array([float(t)]))[0])

    def states(self, times: np.ndarray) -> np.ndarray:
        """(n, 4) x, y, yaw, speed at each of ``times`` (s), at once: the env tabulates an episode's
        worth at its reset and reads one row a physics step."""
        s, v = self._profile(np.asarray(times, float))
        path = self.path
        unwrapped = _unwrapped_headings(self.route)
        yaw = np.interp(s, path.arclength, unwrapped)
        return np.column_stack([np.interp(s, path.arclength, path.points[:, 0]),
                                np.interp(s, path.arclength, path.points[:, 1]),
                                (yaw + np.pi) % (2 * np.pi) - np.pi, v])

    def _profile(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a = TRAFFIC_BRAKE_MPS2
        room = self.stop_s - self.start_s
        # Too close to its stop to reach cruise: it brakes from the start, from the speed that stops it there.
        v = min(self.speed_mps, math.sqrt(2 * a * room))
        braking = v * v / (2 * a)
        t_cruise = (room - braking) / v if v > 0 else 0.0
        tau = np.clip(t - self.depart_t_s, 0.0, None)
        brake = np.clip(tau - t_cruise, 0.0, v / a)
        s = self.start_s + v * np.minimum(tau, t_cruise) + v * brake - 0.5 * a * brake * brake
        speed = np.where(tau >= t_cruise, v - a * brake, v)
        return s, np.where(t < self.depart_t_s, 0.0, speed)

    def to_options(self) -> dict:
        """The env's reset option for this car (``options["traffic"]`` holds a list of them)."""
        return {"route": list(self.route), "start_s_m": self.start_s, "speed_mps": self.speed_mps,
                "stop_s_m": self.stop_s, "colour": self.colour, "depart_t_s": self.depart_t_s}

    @classmethod
    def from_options(cls, raw: object) -> "TrafficCar":
        """A car from its reset option; ValueError names what is wrong."""
        keys = {"route", "start_s_m", "speed_mps", "stop_s_m", "colour", "depart_t_s"}
        if not isinstance(raw, dict) or not {"route", "start_s_m", "speed_mps"} <= set(raw) or set(raw) - keys:
            raise ValueError(f"each options['traffic'] entry is a dict with route, start_s_m, speed_mps (and "
                             f"optionally stop_s_m, colour, depart_t_s), got {raw!r}")
        route = raw["route"]
        if isinstance(route, (str, bytes)) or not all(isinstance(n, numbers.Integral) for n in route):
            raise ValueError(f"a traffic car's route must be road-graph node ids, got {route!r}")
        route = tuple(int(n) for n in route)
        length = _route_path(route).length  # ValueError names a bad edge
        return cls(route, float(raw["start_s_m"]), float(raw["speed_mps"]), float(raw.get("stop_s_m", length)),
                   str(raw.get("colour", "red")), float(raw.get("depart_t_s", 0.0)))


@lru_cache(maxsize=64)
def _route_path(route: tuple[int, ...]) -> Path:
    return qcar2_road_graph().route_path(list(route))


@lru_cache(maxsize=64)
def _unwrapped_headings(route: tuple[int, ...]) -> np.ndarray:
    return np.unwrap(_route_path(route).headings)


def cross_traffic(sign: int, t_ego_s: float, *, gap_s: float = 0.0, speed_mps: float = 1.0,
                  cars: int = 1, colours: tuple[str, ...] | None = None) -> tuple[TrafficCar, ...]:
    """The cross-traffic of an approach to stop sign ``sign``, timed to the conflict point.

    Had the ego car not stopped, its body origin would pass the conflict point at ``t_ego_s``
    (the scenario plan works it out from the car's route and speed). Car k's body origin passes
    it at t_ego + ``gap_s`` + k x ``HEADWAY_S``, at ``speed_mps``; its route runs back through
    the road graph as far as that needs and on past the conflict.
    """
    if not (isinstance(cars, numbers.Integral) and 1 <= cars <= MAX_TRAFFIC_CARS):
        raise ValueError(f"cars must be an int in 1..{MAX_TRAFFIC_CARS}, got {cars!r}")
    if not (isinstance(gap_s, numbers.Real) and -5.0 <= gap_s <= 5.0):
        raise ValueError(f"gap_s must be in [-5, 5] s, got {gap_s!r}")
    if not (isinstance(speed_mps, numbers.Real) and 0.1 <= speed_mps <= 3.0):
        raise ValueError(f"speed_mps must be in [0.1, 3.0] m/s, got {speed_mps!r}")
    colours = tuple(colours) if colours is not None else tuple(TRAFFIC_COLOURS)[:cars]
    if len(colours) != cars:
        raise ValueError(f"give one colour per car ({cars}), got {colours!r}")
    if not (isinstance(t_ego_s, numbers.Real) and 0.0 <= t_ego_s <= 60.0):
        raise ValueError(f"t_ego_s must be in [0, 60] s, got {t_ego_s!r}")
    conflict = conflict_of(sign)
    t_ego = float(t_ego_s)
    out = []
    for k in range(cars):
        run_up = speed_mps * max(0.0, t_ego + gap_s + k * HEADWAY_S)
        route, lane_start = _route_through(conflict.lane, run_up - conflict.lane_s, stop_signs()[sign])
        s_conflict = lane_start + conflict.lane_s
        path = _route_path(route)
        stop_s = _first_stop_line(path, s_conflict) or path.length
        start_s = max(0.0, s_conflict - run_up)
        depart = (run_up - s_conflict) / speed_mps if run_up > s_conflict else 0.0
        out.append(TrafficCar(route, start_s, float(speed_mps), stop_s, colours[k], depart))
    return tuple(out)


def _route_through(lane: tuple[int, int], back_m: float, ego_sign: StopSign) -> tuple[tuple[int, ...], float]:
    """A route along ``lane`` with up to ``back_m`` of road before the lane's start and
    ``_CLEAR_AFTER_M`` after it; (nodes, arclength where ``lane`` starts). Back it takes the
    lowest-numbered neighbour that leaves the ego car's approach route alone and meets no stop
    sign, as long as there is one; on, the lowest-numbered successor."""
    graph = qcar2_road_graph()
    avoid = set(ego_sign.route)
    route, before = list(lane), 0.0
    while before < back_m:
        preds = [n for n in sorted(graph.nodes) if (n, route[0]) in graph.paths and n not in avoid and n not in route
                 and not _faces_a_stop_line(graph.route_path([n, *route]))]
        if not preds:  # the car waits here (``TrafficCar.depart_t_s``)
            break
        before += graph.paths[(preds[0], route[0])].length
        route.insert(0, preds[0])
    after = graph.paths[lane].length
    while after < _CLEAR_AFTER_M + graph.paths[lane].length:
        succs = [n for n in graph.successors(route[-1]) if n not in route]
        if not succs:
            break
        after += graph.paths[(route[-1], succs[0])].length
        route.append(succs[0])
    return tuple(route), before


def _faces_a_stop_line(path: Path) -> bool:
    return any(t.kind == "sign" for t in targets_on_path(path, None, -10.0))


def _first_stop_line(path: Path, after_s: float) -> float | None:
    """Where a car on ``path`` must stop: the first stop line facing it past ``after_s`` (minus its
    bumper's reach); None when none faces it. One facing it before ``after_s`` is refused."""
    for target in targets_on_path(path, None, 0.0):
        if target.stop_s < after_s:
            raise ValueError(f"a stop sign ({target.name}) faces this car's route before its conflict point")
        return max(after_s, target.stop_s - CAR_FOOTPRINT_M[0] / 2)  # its front bumper on the line
    return None
