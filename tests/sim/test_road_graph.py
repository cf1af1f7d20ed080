"""Road graph of the indoor map: centrelines through the official nodes, edge geometry, routes, projection."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.sim.world import map_facts
from racf.sim.world.road_graph import Path, qcar2_road_graph, scs_path

GRAPH = qcar2_road_graph()
EDGE_IDS = [f"{a}-{b}{letter}" for a, b, letter in map_facts.EDGES]


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _node_xy(n: int) -> np.ndarray:
    return np.array(map_facts.NODES[n][:2])


def _node_heading(n: int) -> float:
    return math.radians(map_facts.NODES[n][2])


def _point_to_polyline(p: np.ndarray, pts: np.ndarray) -> float:
    a, d = pts[:-1], np.diff(pts, axis=0)
    t = np.clip(((p - a) * d).sum(1) / np.maximum((d**2).sum(1), 1e-12), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))


def _geometric_headings(pts: np.ndarray) -> np.ndarray:
    d = np.diff(pts, axis=0)
    return np.arctan2(d[:, 1], d[:, 0])


# The published facts (shared/reference/qcar2.md), copied independently of map_facts.
_PUBLISHED_NODES = """
0 0 0.130 -90 | 1 0.269 0.081 90 | 2 1.127 -1.085 0 | 3 1.127 -0.814 180 | 4 2.255 0.081 90
5 1.984 0.081 -90 | 6 1.013 1.101 180 | 7 1.235 0.830 0 | 8 -0.749 1.101 180 | 9 -0.749 0.830 0
10 -1.282 -0.460 -42 | 11 0 2.163 -90 | 12 0 1.850 -90 | 13 0.269 1.850 90 | 14 2.255 2.967 90
15 1.984 1.850 -90 | 16 0.908 3.710 -80.6 | 17 1.466 3.151 -9.4 | 18 0.623 3.067 -138
19 0.792 2.859 42 | 20 0 4.497 180 | 21 0 4.227 0 | 22 -1.984 2.967 -90 | 23 -1.716 2.967 90
"""
_PUBLISHED_EDGES = """
0-2o 1-7i 1-8o 2-4o 3-1i 4-6o 5-3i 6-0o 6-8s 7-5i 8-10w 9-0i 9-7s 10-1i 10-2i
1-13s 4-14s 6-13i 7-14o 8-23i 9-13o 11-12s 12-0s 12-7o 12-8i 13-19i 14-16c 14-20c
15-5o 15-6i 16-17c 16-18i 17-15i 17-16c 17-20c 18-11k 19-17i 20-22o 21-16i 22-9o 22-10o 23-21i
"""
_PUBLISHED_RADII = {"s": None, "i": 0.6217, "o": 0.8913, "c": 0.6777, "w": 0.7122, "k": 0.7631}


def test_map_facts_match_published_graph():
    nodes = {}
    for item in _PUBLISHED_NODES.replace("\n", "|").split("|"):
        if item.strip():
            n, x, y, h = item.split()
            nodes[int(n)] = (float(x), float(y), float(h))
    assert map_facts.NODES == nodes
    edges = sorted((int(t.split("-")[0]), int(t.split("-")[1][:-1]), t[-1]) for t in _PUBLISHED_EDGES.split())
    assert sorted(map_facts.EDGES) == edges
    assert map_facts.ARC_RADII_M == _PUBLISHED_RADII


def test_graph_has_all_official_edges():
    assert sorted(GRAPH.edges) == sorted((a, b) for a, b, _ in map_facts.EDGES)
    assert len(GRAPH.edges) == 42
    assert set(GRAPH.nodes) == set(map_facts.NODES)


@pytest.mark.parametrize("node", sorted(map_facts.NODES))
def test_centrelines_pass_through_every_official_node(node):
    xy = _node_xy(node)
    touching = [(k, p) for k, p in GRAPH.paths.items() if node in k]
    assert touching, f"node {node} is on no edge"
    for (a, b), path in touching:
        end = path.points[0] if a == node else path.points[-1]
        assert np.linalg.norm(end - xy) <= 0.01, f"edge {a}-{b} misses node {node}"
    nearest = min(_point_to_polyline(xy, p.points) for p in GRAPH.paths.values())
    assert nearest <= 0.01


@pytest.mark.parametrize("edge", map_facts.EDGES, ids=EDGE_IDS)
def test_edge_headings_continuity_and_curvature(edge):
    a, b, letter = edge
    path = GRAPH.paths[(a, b)]
    pts = path.points
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert steps.max() <= 0.011, "gap in the polyline"
    assert path.length == pytest.approx(steps.sum())

    # Heading of travel (from the geometry) at both ends matches the node poses.
    geo = _geometric_headings(pts)
    assert abs(_wrap(geo[0] - _node_heading(a))) <= math.radians(2.0)
    assert abs(_wrap(geo[-1] - _node_heading(b))) <= math.radians(2.0)
    # The stored headings agree with the geometry everywhere (segment midpoints vs points).
    assert np.abs(_wrap(path.headings[:-1] - geo)).max() <= math.radians(1.0)
    assert np.abs(_wrap(path.headings[1:] - geo)).max() <= math.radians(1.0)

    # Geometric curvature at interior points: heading change per metre.
    mask = steps > 1e-3  # skip the rare clipped, near-zero-length joint segments
    h, s = geo[mask], steps[mask]
    k = _wrap(np.diff(h)) / (0.5 * (s[1:] + s[:-1]))
    turn = float(np.sum(_wrap(np.diff(h))))
    radius = map_facts.ARC_RADII_M[letter]
    curved = np.abs(k) > 0.2
    if not curved.any():
        # A straight edge (or an arc edge between collinear poses): ends on the start's heading line.
        assert abs(_wrap(_node_heading(b) - _node_heading(a))) < 1e-6
        chord = _node_xy(b) - _node_xy(a)
        u = np.array([math.cos(_node_heading(a)), math.sin(_node_heading(a))])
        assert abs(u[0] * chord[1] - u[1] * chord[0]) <= 0.01
        return
    assert radius is not None, f"straight edge {a}-{b} bends"
    # The arc has the letter's radius, with one sign (a single turn direction).
    assert np.median(np.abs(k[curved])) == pytest.approx(1.0 / radius, rel=0.01)
    assert np.abs(k).max() <= 1.01 / radius
    assert len(set(np.sign(k[curved]))) == 1
    # The stored curvature agrees with the geometry.
    assert set(np.round(np.abs(path.curvature[path.curvature != 0]) * radius, 6)) == {1.0}
    assert np.sign(path.curvature[path.curvature != 0][0]) == np.sign(k[curved][0])
    # The total turn joins the two headings.
    assert abs(_wrap(turn - (_node_heading(b) - _node_heading(a)))) <= math.radians(2.0)


def test_scs_path_rejects_impossible_straight():
    with pytest.raises(ValueError):
        scs_path((0.0, 0.0, 0.0), (1.0, 0.5, 0.0), None)


def _dijkstra(start: int, goal: int) -> float:
    dist = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, n = heapq.heappop(heap)
        if n == goal:
            return d
        if d > dist.get(n, math.inf):
            continue
        for (a, b), p in GRAPH.paths.items():
            if a == n and d + p.length < dist.get(b, math.inf):
                dist[b] = d + p.length
                heapq.heappush(heap, (dist[b], b))
    return math.inf


@pytest.mark.parametrize("start, goal", [(0, 14), (16, 5), (6, 21), (10, 20), (3, 22), (21, 21)])
def test_shortest_route_is_connected_and_shortest(start, goal):
    route = GRAPH.shortest_route(start, goal)
    assert route[0] == start and route[-1] == goal
    for a, b in zip(route, route[1:]):
        assert (a, b) in GRAPH.paths
    edge_sum = sum(GRAPH.paths[(a, b)].length for a, b in zip(route, route[1:]))
    assert edge_sum == pytest.approx(_dijkstra(start, goal), abs=1e-9)
    if len(route) >= 2:
        path = GRAPH.route_path(route)
        assert path.length == pytest.approx(edge_sum, abs=1e-6)
        assert np.linalg.norm(path.points[0] - _node_xy(start)) <= 0.01
        assert np.linalg.norm(path.points[-1] - _node_xy(goal)) <= 0.01
        assert np.linalg.norm(np.diff(path.points, axis=0), axis=1).max() <= 0.011


@pytest.mark.parametrize("start, goal", [(0, 99), (-1, 3), (99, 0)])
def test_shortest_route_unknown_node(start, goal):
    with pytest.raises(ValueError, match="99|-1"):
        GRAPH.shortest_route(start, goal)


def test_route_path_rejects_non_edges():
    with pytest.raises(ValueError):
        GRAPH.route_path([0, 14])
    with pytest.raises(ValueError):
        GRAPH.route_path([0])


def _assert_projects_back(path, s, offset):
    """A point ``offset`` m left of the path at ``s`` projects to ``s`` with that lateral offset."""
    x, y, h = path.pose_at(s)
    s_proj, lateral = path.project(np.array([x, y]) + offset * np.array([-math.sin(h), math.cos(h)]))
    assert lateral == pytest.approx(offset, abs=2e-3)
    assert s_proj == pytest.approx(s, abs=0.01)


@pytest.mark.parametrize("edge", [(0, 2), (6, 8), (17, 16), (13, 19)])
@pytest.mark.parametrize("offset", [0.1, -0.1])
def test_project_offset_point(edge, offset):
    path = GRAPH.paths[edge]
    for frac in (0.25, 0.5, 0.75):
        _assert_projects_back(path, frac * path.length, offset)


def test_project_with_hint_stays_on_branch():
    # Twice round the roundabout: every point of the first lap is passed again one lap later.
    path = GRAPH.route_path([16, 17, 16, 17])
    lap = GRAPH.paths[(16, 17)].length + GRAPH.paths[(17, 16)].length
    s_first = 0.3
    x, y, _ = path.pose_at(s_first)
    assert np.allclose(path.pose_at(s_first + lap)[:2], (x, y), atol=0.01)
    s, lat = path.project(np.array([x, y]), s_hint=s_first + lap - 0.05, window_m=0.3)
    assert s == pytest.approx(s_first + lap, abs=0.01)
    assert abs(lat) < 2e-3
    s, lat = path.project(np.array([x, y]), s_hint=s_first + 0.05, window_m=0.3)
    assert s == pytest.approx(s_first, abs=0.01)


_SAMPLE_EDGES = [(0, 2), (1, 8), (14, 16), (17, 16), (18, 11), (6, 8), (8, 10)]


@settings(max_examples=150, deadline=None)
@given(edge=st.sampled_from(_SAMPLE_EDGES), frac=st.floats(0.0, 1.0))
def test_project_inverts_pose_at(edge, frac):
    path = GRAPH.paths[edge]
    s = frac * path.length
    x, y, h = path.pose_at(s)
    s_proj, lateral = path.project(np.array([x, y]))
    assert s_proj == pytest.approx(s, abs=0.01)
    assert abs(lateral) <= 1e-3
    # The heading at s is the direction of travel there.
    x2, y2, _ = path.pose_at(min(s + 0.02, path.length))
    x1, y1, _ = path.pose_at(max(s - 0.02, 0.0))
    assert abs(_wrap(math.atan2(y2 - y1, x2 - x1) - h)) <= math.radians(3.0)


@settings(max_examples=100, deadline=None)
@given(frac=st.floats(0.0, 1.0), offset=st.floats(-0.12, 0.12))
def test_project_lateral_offset_property(frac, offset):
    path = GRAPH.paths[(8, 10)]
    # Away from the ends, where the nearest point is the foot.
    _assert_projects_back(path, frac * (path.length - 0.3) + 0.15, offset)


def test_path_validation():
    with pytest.raises(ValueError):
        Path(np.zeros((1, 2)), np.zeros(1), np.zeros(1))
    with pytest.raises(ValueError):
        Path.concat([])
