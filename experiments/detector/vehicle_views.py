"""The vehicle segmenter's views: the car's camera on a lane of the map with a QCar 2 somewhere ahead.

Each view puts the car on one of the map's approaches (along the lane, as it drives: a little off
the lane's centre, a little turned) and the other car ahead on the same lane, ``LEAD_RANGE_M``
away, a little off its centre and turned, in one of the four paints (the net must find a car,
not a colour); in some views it stands on another lane, crosswise, and in some there is none.
The room's light is drawn as for the sign segmenter's views. The mask is exact and needs no
projection: the frame rendered with the other car and without it differ in depth where it is.
"""

from __future__ import annotations

import math

import numpy as np

from racf.experiments.detector.views import ViewRenderer
from racf.sim.world.lead_manager import LEAD_PREFIX, LeadManager
from racf.sim.world.road_graph import qcar2_road_graph
from racf.sim.world.stop_signs import stop_signs
from racf.sim.world.traffic import TRAFFIC_COLOURS
from racf.sim.world.traffic_manager import PARKED_Z_M, traffic_body, traffic_paint_geoms

__all__ = ["VehicleViews", "LEAD_RANGE_M", "NO_CAR_P", "CROSSWISE_P"]

#: How far ahead of the camera the other car's centre stands, m.
LEAD_RANGE_M = (0.35, 3.0)
#: Share of views with no other car (negatives), and with one on another lane, crosswise.
NO_CAR_P, CROSSWISE_P = 0.15, 0.2
#: A pixel whose depth the other car changes by more than this is the car's, m.
_MASK_DEPTH_M = 0.01


class VehicleViews:
    """Renders views with the env's own camera and a lead car's body (a ``LeadManager``'s)."""

    def __init__(self) -> None:
        self.renderer = ViewRenderer(world=(LeadManager(),))
        m = self.renderer.model
        self._mocap = int(m.body_mocapid[m.body(traffic_body(0, LEAD_PREFIX)).id])
        self._paint = [m.geom(g).id for g in traffic_paint_geoms(0, LEAD_PREFIX)]
        self._edges = list(qcar2_road_graph().paths.values())

    def draw(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, float]:
        """One view: (rgb (H, W, 3) uint8, mask (H, W) bool of the other car's pixels, its range m or NaN)."""
        from racf.experiments.detector.approach_views import draw_approach_view

        r = self.renderer
        spec = draw_approach_view(rng, r.camera_offset)
        sign = stop_signs()[spec.sign]
        u = rng.random()
        car = None
        if u >= NO_CAR_P:
            if u < NO_CAR_P + CROSSWISE_P:
                path = self._edges[int(rng.integers(len(self._edges)))]
                s = float(rng.uniform(0.0, path.length))
            else:
                path = sign.path
                s_cam, _ = path.project(np.asarray(spec.camera_xy))
                s = s_cam + float(rng.uniform(*LEAD_RANGE_M))
            x, y, heading = path.pose_at(s)
            lateral = float(rng.normal(0.0, 0.03))
            car = (x - math.sin(heading) * lateral, y + math.cos(heading) * lateral,
                   heading + float(rng.normal(0.0, math.radians(8.0))))
            r.model.geom_rgba[self._paint] = TRAFFIC_COLOURS[tuple(TRAFFIC_COLOURS)[int(rng.integers(len(TRAFFIC_COLOURS)))]]
        self._place(None)
        empty = r.render(spec)
        empty_depth = r.last_depth
        if car is None:
            return empty.rgb, np.zeros(empty.rgb.shape[:2], bool), math.nan
        self._place(car)
        view = r.render(spec)
        mask = np.abs(r.last_depth - empty_depth) > _MASK_DEPTH_M
        return view.rgb, mask, float(math.hypot(car[0] - spec.camera_xy[0], car[1] - spec.camera_xy[1]))

    def _place(self, car: tuple[float, float, float] | None) -> None:
        d = self.renderer.data
        if car is None:
            d.mocap_pos[self._mocap] = (0.0, 0.0, PARKED_Z_M)
            d.mocap_quat[self._mocap] = (1.0, 0.0, 0.0, 0.0)
        else:
            x, y, yaw = car
            d.mocap_pos[self._mocap] = (x, y, 0.0)
            d.mocap_quat[self._mocap] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))

    def close(self) -> None:
        self.renderer.restore()
        self.renderer.close()
