"""A parked van that hides the stop sign for the far part of the approach: an example racf scenario.

The van stands at the kerb on the sign's side, ``ahead_m`` before the sign, its inner side
``kerb_gap_m`` from the lane's centre line. From far away the camera's line of sight to the sign
passes through it; closer in, the sign comes out from behind it. The car must then detect,
confirm and brake in what is left of the approach: a van further up the lane hides the sign for
longer.

The scenario declares its parameters once (:class:`~racf.experiments.scenarios.Param`); the plan
places the van from the map (the sign's place and the lane), never from the running simulation,
and a world manager (:class:`ParkedVan`) puts it there at each reset. Nothing in racf names it.
"""

from __future__ import annotations

import math

import numpy as np

from racf.experiments.scenarios import Param, Scenario, WorldManager

__all__ = ["ParkedCar", "ParkedVan"]

#: The van's length, width and height, m (a box at the QCar 2's scale: it hides a sign on its pole).
VAN_SIZE_M = (0.40, 0.22, 0.35)
_BELOW_FLOOR_M = -5.0


class ParkedVan(WorldManager):
    """A van (a mocap box the camera, the LiDAR and the car's chassis all meet) placed at each reset
    by the reset option ``parked_van``: ``{"x": m, "y": m, "yaw": rad}``, or absent: out of sight."""

    name = "parked_van"
    option = "parked_van"

    def scene_xml(self) -> str:
        lx, ly, h = VAN_SIZE_M
        return f"""
    <body name="parked_van" mocap="true" pos="0 0 {_BELOW_FLOOR_M}">
      <geom name="parked_van" type="box" pos="0 0 {h / 2}" size="{lx / 2} {ly / 2} {h / 2}" rgba="0.85 0.85 0.80 1"/>
    </body>"""

    def bind(self, model) -> None:
        self._mocap = int(model.body_mocapid[model.body("parked_van").id])

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        if value is None:
            return  # mj_resetData left it below the floor
        data.mocap_pos[self._mocap] = (float(value["x"]), float(value["y"]), 0.0)
        yaw = float(value["yaw"])
        data.mocap_quat[self._mocap] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))


class ParkedCar(Scenario):
    """A stop-sign approach with a van parked at the kerb before the sign, hiding it from far away."""

    name = "parked_car"
    meaning = "a stop-sign approach with a van parked before the sign, hiding it from far away"
    target = "sign"
    params = (
        Param("ahead_m", 0.5, 0.2, 2.5, unit="m", meaning="how far before the sign the van's downstream end stands"),
        Param("kerb_gap_m", 0.16, 0.14, 0.4, unit="m", meaning="from the lane's centre line to the van's inner side"),
    )

    def world(self, spec, values):
        return (ParkedVan(),)

    def plan(self, spec, values, draft):
        path, sign = draft.mission.path, draft.mission.targets[0].target
        s_sign, _ = path.project(np.asarray(sign.position[:2], float))
        lx, ly, _ = VAN_SIZE_M
        s_van = s_sign - values["ahead_m"] - lx / 2
        k = int(np.clip(np.searchsorted(path.arclength, s_van), 0, len(path.arclength) - 1))
        point, heading = path.points[k], float(path.headings[k])
        left = np.array([-math.sin(heading), math.cos(heading)])
        side = 1.0 if float(np.dot(np.asarray(sign.position[:2]) - point, left)) > 0 else -1.0
        x, y = point + side * (values["kerb_gap_m"] + ly / 2) * left
        options = {**draft.reset_options, "parked_van": {"x": float(x), "y": float(y), "yaw": heading}}
        return self.replace(draft, reset_options=options)
