"""The indoor map's road graph: lane-centre paths between official node poses.

Every edge is a straight-arc-straight path (Quanser's SCS construction): leave the start
node along its heading, turn on a circle of the edge's radius, and arrive at the end node
along its heading. Paths are dense polylines (1 cm spacing) so that routes, projections and
drawing all use one representation. Pure numpy: nothing here knows MuJoCo.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import networkx as nx
import numpy as np

from racf.sim.world import map_facts

__all__ = ["Path", "RoadGraph", "scs_path", "qcar2_road_graph"]

_SPACING_M = 0.01
#: A straight leg may be this much negative (rounding in the published poses) and is clipped.
_LEG_TOLERANCE_M = 0.01


def _unit(heading: float) -> np.ndarray:
    return np.array([math.cos(heading), math.sin(heading)])


def _left(heading: float) -> np.ndarray:
    return np.array([-math.sin(heading), math.cos(heading)])


def _cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _wrap(angle: np.ndarray | float) -> np.ndarray | float:
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


@dataclass(frozen=True)
class Path:
    """A lane-centre polyline in the map frame.

    Attributes:
        points: (N, 2) x, y in metres.
        headings: (N,) heading of travel in radians at each point.
        curvature: (N,) signed curvature in 1/m (left turn positive).
    """

    points: np.ndarray
    headings: np.ndarray
    curvature: np.ndarray
    arclength: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        points = np.asarray(self.points, dtype=float)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2:
            raise ValueError(f"Path.points must have shape (N>=2, 2), got {points.shape}")
        steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "arclength", np.concatenate([[0.0], np.cumsum(steps)]))

    @property
    def length(self) -> float:
        """Total length in metres."""
        return float(self.arclength[-1])

    def pose_at(self, s: float) -> tuple[float, float, float]:
        """(x, y, heading) at arclength ``s`` metres, clipped to the path."""
        s = float(np.clip(s, 0.0, self.length))
        i = int(np.clip(np.searchsorted(self.arclength, s) - 1, 0, len(self.points) - 2))
        seg = self.arclength[i + 1] - self.arclength[i]
        t = 0.0 if seg <= 0 else (s - self.arclength[i]) / seg
        xy = (1 - t) * self.points[i] + t * self.points[i + 1]
        dh = float(_wrap(self.headings[i + 1] - self.headings[i]))
        return float(xy[0]), float(xy[1]), float(_wrap(self.headings[i] + t * dh))

    def project(self, xy: np.ndarray, s_hint: float | None = None, window_m: float = 1.0
                ) -> tuple[float, float]:
        """Nearest point on the path to ``xy``.

        Args:
            xy: (2,) point in the map frame, metres.
            s_hint: search only within ``window_m`` of this arclength (keeps the match on
                the right branch where a route crosses itself).
            window_m: half-width of the search window in metres.

        Returns:
            (s, lateral): arclength of the nearest point and the signed lateral offset of
            ``xy`` from the path (left of travel positive), metres.
        """
        xy = np.asarray(xy, dtype=float)
        lo, hi = 0, len(self.points) - 1
        if s_hint is not None:
            lo = int(np.searchsorted(self.arclength, s_hint - window_m))
            hi = int(np.searchsorted(self.arclength, s_hint + window_m))
            lo, hi = max(0, min(lo, len(self.points) - 2)), max(lo + 1, min(hi, len(self.points) - 1))
        a = self.points[lo:hi]
        d = self.points[lo + 1 : hi + 1] - a
        seg_len2 = np.maximum((d**2).sum(axis=1), 1e-12)
        t = np.clip(((xy - a) * d).sum(axis=1) / seg_len2, 0.0, 1.0)
        foot = a + t[:, None] * d
        k = int(np.argmin(((foot - xy) ** 2).sum(axis=1)))
        s = self.arclength[lo + k] + t[k] * math.sqrt(seg_len2[k])
        rel = xy - foot[k]
        lateral = float(d[k, 0] * rel[1] - d[k, 1] * rel[0]) / math.sqrt(seg_len2[k])
        return float(s), lateral

    def offset(self, lateral_m: float) -> np.ndarray:
        """(N, 2) polyline shifted ``lateral_m`` to the left of travel."""
        normals = np.column_stack([-np.sin(self.headings), np.cos(self.headings)])
        return self.points + lateral_m * normals

    @staticmethod
    def concat(paths: list["Path"]) -> "Path":
        """Join paths end to start, dropping the duplicated joint points."""
        if not paths:
            raise ValueError("Path.concat needs at least one path")
        pts, hds, curv = [paths[0].points], [paths[0].headings], [paths[0].curvature]
        for p in paths[1:]:
            skip = 1 if np.allclose(p.points[0], pts[-1][-1], atol=1e-6) else 0
            pts.append(p.points[skip:])
            hds.append(p.headings[skip:])
            curv.append(p.curvature[skip:])
        return Path(np.concatenate(pts), np.concatenate(hds), np.concatenate(curv))


def _straight(p0: np.ndarray, p1: np.ndarray, heading: float) -> tuple[np.ndarray, ...]:
    n = max(2, int(math.ceil(np.linalg.norm(p1 - p0) / _SPACING_M)) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    return (1 - t) * p0 + t * p1, np.full(n, heading), np.zeros(n)


def scs_path(start: tuple[float, float, float], end: tuple[float, float, float],
             radius_m: float | None) -> Path:
    """Straight-arc-straight path between two poses.

    Args:
        start: (x m, y m, heading rad) of the start node.
        end: (x m, y m, heading rad) of the end node.
        radius_m: arc radius; ``None`` for a straight edge.

    Returns:
        The path. It starts exactly at ``start`` and ends exactly at ``end``.

    Raises:
        ValueError: if no straight-arc-straight path with non-negative legs joins the poses.
    """
    p1, p2 = np.array(start[:2], float), np.array(end[:2], float)
    h1, h2 = float(start[2]), float(end[2])
    chord = p2 - p1
    parallel = abs(math.sin(h2 - h1)) < 1e-6 and math.cos(h2 - h1) > 0
    if radius_m is None or (parallel and abs(_cross(_unit(h1), chord)) < 1e-3):
        if abs(_cross(_unit(h1), chord)) > _LEG_TOLERANCE_M:
            raise ValueError(f"straight edge from {start} to {end}: end is off the start heading")
        pts, hds, crv = _straight(p1, p2, h1)
        return Path(pts, hds, crv)

    best: tuple[float, float, float, int] | None = None
    for turn in (1, -1):  # +1 left (counter-clockwise), -1 right
        rhs = chord + turn * radius_m * (_left(h2) - _left(h1))
        try:
            a, b = np.linalg.solve(np.column_stack([_unit(h1), _unit(h2)]), rhs)
        except np.linalg.LinAlgError:
            continue
        if a < -_LEG_TOLERANCE_M or b < -_LEG_TOLERANCE_M:
            continue
        sweep = (turn * (h2 - h1)) % (2 * math.pi)
        length = max(a, 0) + max(b, 0) + radius_m * sweep
        if best is None or length < best[0]:
            best = (length, max(float(a), 0.0), float(sweep), turn)
    if best is None:
        raise ValueError(f"no straight-arc-straight path of radius {radius_m} m from {start} to {end}")
    _, a, sweep, turn = best

    q1 = p1 + a * _unit(h1)
    centre = q1 + turn * radius_m * _left(h1)
    n_arc = max(2, int(math.ceil(radius_m * sweep / _SPACING_M)) + 1)
    phi0 = math.atan2(*(q1 - centre)[::-1])
    phis = phi0 + turn * np.linspace(0.0, sweep, n_arc)
    arc = centre + radius_m * np.column_stack([np.cos(phis), np.sin(phis)])
    arc_h = h1 + turn * np.linspace(0.0, sweep, n_arc)

    pieces_p, pieces_h, pieces_c = [], [], []
    if a > 1e-6:
        lp, lh, lc = _straight(p1, q1, h1)
        pieces_p.append(lp[:-1]); pieces_h.append(lh[:-1]); pieces_c.append(lc[:-1])
    # Where the last leg is (within tolerance) negative, the arc ends on p2: clip it there.
    along = (arc - p2) @ _unit(h2)
    n_keep = n_arc
    while n_keep > 1 and along[n_keep - 1] > 1e-9:
        n_keep -= 1
    pieces_p.append(arc[:n_keep]); pieces_h.append(arc_h[:n_keep])
    pieces_c.append(np.full(n_keep, turn / radius_m))
    q2 = arc[n_keep - 1]
    lp, lh, lc = _straight(q2, p2, h2)
    pieces_p.append(lp[1:]); pieces_h.append(lh[1:]); pieces_c.append(lc[1:])
    return Path(np.concatenate(pieces_p), _wrap(np.concatenate(pieces_h)), np.concatenate(pieces_c))


class RoadGraph:
    """Directed lane graph of the map with a path on every edge; plans routes.

    Args:
        nodes: id -> (x m, y m, heading deg).
        edges: (start, end, radius letter) triples.
        radii_m: radius per letter, ``None`` for straight.
    """

    def __init__(self, nodes: dict[int, tuple[float, float, float]],
                 edges: tuple[tuple[int, int, str], ...],
                 radii_m: dict[str, float | None]) -> None:
        self.nodes = {k: (x, y, math.radians(h)) for k, (x, y, h) in nodes.items()}
        self.paths: dict[tuple[int, int], Path] = {}
        self._graph = nx.DiGraph()
        for start, end, letter in edges:
            if start not in self.nodes or end not in self.nodes:
                raise ValueError(f"edge {start}-{end} names an unknown node")
            if letter not in radii_m:
                raise ValueError(f"edge {start}-{end}: unknown radius letter {letter!r}, allowed {sorted(radii_m)}")
            path = scs_path(self.nodes[start], self.nodes[end], radii_m[letter])
            self.paths[(start, end)] = path
            self._graph.add_edge(start, end, length=path.length)

    @property
    def edges(self) -> list[tuple[int, int]]:
        return list(self.paths)

    def successors(self, node: int) -> list[int]:
        return sorted(self._graph.successors(node))

    def shortest_route(self, start: int, goal: int) -> list[int]:
        """Node ids of the shortest route by length from ``start`` to ``goal``."""
        for n in (start, goal):
            if n not in self.nodes:
                raise ValueError(f"unknown node {n}; nodes are 0..{max(self.nodes)}")
        try:
            return nx.shortest_path(self._graph, start, goal, weight="length")
        except nx.NetworkXNoPath as err:
            raise ValueError(f"no route from node {start} to node {goal}") from err

    def route_path(self, route: list[int]) -> Path:
        """The joined path along consecutive nodes of ``route``."""
        if len(route) < 2:
            raise ValueError("a route needs at least two nodes")
        missing = [(a, b) for a, b in zip(route, route[1:]) if (a, b) not in self.paths]
        if missing:
            raise ValueError(f"route uses edges that are not in the graph: {missing}")
        return Path.concat([self.paths[(a, b)] for a, b in zip(route, route[1:])])


_GRAPH: RoadGraph | None = None


def qcar2_road_graph() -> RoadGraph:
    """The official QCar 2 map road graph (built once, then shared; treat as read-only)."""
    global _GRAPH
    if _GRAPH is None:
        _GRAPH = RoadGraph(map_facts.NODES, map_facts.EDGES, map_facts.ARC_RADII_M)
    return _GRAPH
