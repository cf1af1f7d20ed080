"""Paints the map's floor mat from the road graph: asphalt, edge lines, centre lines, stop lines.

The road is every point within ``ROAD_HALF_WIDTH_M`` of some lane centreline (so two
opposite lanes 0.27 m apart merge into one two-lane road), with a white edge band outside
it. A yellow centre line is drawn on a lane's left offset wherever another lane runs there,
which marks two-way roads and leaves one-way arcs (the roundabout) without one.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np
from scipy.spatial import cKDTree

from racf.sim.world import map_facts
from racf.sim.world.road_graph import RoadGraph, qcar2_road_graph
from racf.sim.world.stop_signs import stop_signs

__all__ = ["MatGeometry", "render_mat", "mat_png_bytes", "mat_geometry"]

ROAD_HALF_WIDTH_M = 0.15
EDGE_LINE_WIDTH_M = 0.015
CENTRE_LINE_WIDTH_M = 0.012
STOP_LINE_SIZE_M = (0.27, 0.02)  # across the lane, along it
PX_PER_M = 200

_BG = (178, 182, 176)       # light concrete (RGB)
_ASPHALT = (52, 54, 58)
_WHITE = (235, 235, 230)
_YELLOW = (230, 190, 40)


class MatGeometry:
    """Maps the mat's pixels to the map frame: row 0 is the north wall, column 0 the west wall."""

    def __init__(self, px_per_m: int = PX_PER_M) -> None:
        self.x_min, self.x_max, self.y_min, self.y_max = map_facts.WALL_BOUNDS_M
        self.px_per_m = px_per_m
        self.width = int(round((self.x_max - self.x_min) * px_per_m))
        self.height = int(round((self.y_max - self.y_min) * px_per_m))

    def to_px(self, xy: np.ndarray) -> np.ndarray:
        """(N, 2) map metres -> (N, 2) float pixel (column, row)."""
        xy = np.atleast_2d(xy)
        return np.column_stack([(xy[:, 0] - self.x_min) * self.px_per_m,
                                (self.y_max - xy[:, 1]) * self.px_per_m])


def mat_geometry() -> MatGeometry:
    return MatGeometry()


def _polyline(img: np.ndarray, geo: MatGeometry, xy: np.ndarray, colour, width_m: float) -> None:
    pts = np.round(geo.to_px(xy) * 16).astype(np.int32)  # 4 fractional bits
    cv2.polylines(img, [pts], False, colour, max(1, int(round(width_m * geo.px_per_m))),
                  lineType=cv2.LINE_AA, shift=4)


def render_mat(graph: RoadGraph | None = None, px_per_m: int = PX_PER_M) -> np.ndarray:
    """The mat as an (H, W, 3) uint8 RGB image, north up."""
    graph = graph or qcar2_road_graph()
    geo = MatGeometry(px_per_m)
    centre = np.zeros((geo.height, geo.width), np.uint8)
    for path in graph.paths.values():
        _polyline(centre, geo, path.points, 255, 1.0 / px_per_m)
    dist_m = cv2.distanceTransform((centre < 64).astype(np.uint8), cv2.DIST_L2, 5) / px_per_m

    img = np.empty((geo.height, geo.width, 3), np.uint8)
    img[:] = _BG
    img[dist_m <= ROAD_HALF_WIDTH_M + EDGE_LINE_WIDTH_M] = _WHITE
    img[dist_m <= ROAD_HALF_WIDTH_M] = _ASPHALT

    lane_spacing = map_facts.LANE_WIDTH_M
    all_pts = np.concatenate([p.points for p in graph.paths.values()])
    owner = np.concatenate([np.full(len(p.points), i) for i, p in enumerate(graph.paths.values())])
    tree = cKDTree(all_pts)
    for i, path in enumerate(graph.paths.values()):
        left = path.offset(lane_spacing / 2)
        # A neighbour lane runs on the left if some other lane's centre lies ~one spacing away.
        probe = path.offset(lane_spacing)
        dist, idx = tree.query(probe, k=8, distance_upper_bound=0.04)
        has_neighbour = ((dist < 0.04) & (owner[np.minimum(idx, len(owner) - 1)] != i)).any(axis=1)
        runs = np.flatnonzero(np.diff(np.concatenate([[0], has_neighbour.astype(int), [0]])))
        for start, stop in zip(runs[::2], runs[1::2]):
            if stop - start >= 3:
                _polyline(img, geo, left[start:stop], _YELLOW, CENTRE_LINE_WIDTH_M)

    across, along = STOP_LINE_SIZE_M
    for sign in stop_signs():
        s = sign.stop_s
        x, y, h = sign.path.pose_at(s)
        c, si = np.cos(h), np.sin(h)
        corners = np.array([[along / 2, across / 2], [along / 2, -across / 2],
                            [-along / 2, -across / 2], [-along / 2, across / 2]])
        world = np.column_stack([x + corners[:, 0] * c - corners[:, 1] * si,
                                 y + corners[:, 0] * si + corners[:, 1] * c])
        cv2.fillPoly(img, [np.round(geo.to_px(world) * 16).astype(np.int32)], _WHITE,
                     lineType=cv2.LINE_AA, shift=4)
    return img


@lru_cache(maxsize=2)
def mat_png_bytes(px_per_m: int = PX_PER_M) -> bytes:
    """PNG bytes of the mat (built once per process)."""
    ok, buf = cv2.imencode(".png", cv2.cvtColor(render_mat(px_per_m=px_per_m), cv2.COLOR_RGB2BGR))
    if not ok:
        raise RuntimeError("could not encode the mat texture as PNG")
    return buf.tobytes()
