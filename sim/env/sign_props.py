"""The stop signs as a stale map meets them: a mapped sign taken away, and a phantom put up.

:class:`SignPropsManager` is a world manager (:mod:`racf.sim.world.manager`). At each reset it reads
the option ``sign_props`` (``{"remove": i, "phantom": j}``, either None) and

- takes stop sign ``i`` off the map's floor (its body goes under the floor, out of every
  sensor's sight), as a sign that was removed while the map still lists it;
- puts up a **phantom** at sign ``j``'s place: the stop sign's picture, its red octagon and white
  border at a real sign's height, printed on a wall panel standing on the floor, with no pole
  (a poster on a wall, "Phantom of the ADAS", Nassi et al., CCS 2020), half a plate out from the
  sign's pole: the panel reaches from the pole's place outwards, so a car in the lane passes it as it
  would the sign.

``info`` reports which sign is gone (``sign_removed``) and where the phantom stands
(``phantom_at``), -1 for none: ground truth, for the referee.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from racf.sim.world.manager import WorldManager

__all__ = ["SignPropsManager", "PHANTOM_PANEL_M", "PHANTOM_BODY"]

#: The phantom's wall panel: width and height, m (the plate is 0.10 across).
PHANTOM_PANEL_M = (0.24, 0.36)
#: Half the stop sign's plate across, m: the picture's near edge lies this far out from its centre.
PLATE_HALF_M = 0.05
#: The phantom's body in the model.
PHANTOM_BODY = "phantom_poster"
_PARKED = np.array([0.0, 0.0, -5.0])
_PANEL_HALF_THICKNESS_M = 0.004


class SignPropsManager(WorldManager):
    """Removes a stop sign and stands a phantom, per the reset option ``sign_props``."""

    name = "sign props"
    option = "sign_props"

    def __init__(self) -> None:
        self._signs: list[tuple[int, np.ndarray]] = []
        self._phantom = -1
        self._removed = -1
        self._placed = -1

    def scene_xml(self) -> str:
        width, height = PHANTOM_PANEL_M
        return f"""
    <body name="{PHANTOM_BODY}" pos="{_PARKED[0]} {_PARKED[1]} {_PARKED[2]}">
      <geom name="{PHANTOM_BODY}_panel" type="box" pos="{-0.003 - _PANEL_HALF_THICKNESS_M} 0 {height / 2}"
            size="{_PANEL_HALF_THICKNESS_M} {width / 2} {height / 2}" rgba="0.78 0.77 0.72 1"/>
      <geom name="{PHANTOM_BODY}_border" type="mesh" mesh="stop_octagon_border" pos="0 0 0.23" rgba="0.97 0.97 0.97 1"
            contype="0" conaffinity="0"/>
      <geom name="{PHANTOM_BODY}_face" type="mesh" mesh="stop_octagon_face" pos="0.001 0 0.23"
            rgba="0.80 0.05 0.06 1" contype="0" conaffinity="0"/>
    </body>"""

    def bind(self, model: mujoco.MjModel) -> None:
        from racf.sim.world.stop_signs import stop_signs

        self._signs = [(model.body(f"stop_sign_{s.index}").id, model.body(f"stop_sign_{s.index}").pos.copy())
                       for s in stop_signs()]
        self._phantom = model.body(PHANTOM_BODY).id
        self._panel = model.geom(f"{PHANTOM_BODY}_panel").id

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        value = {} if value is None else value
        if not isinstance(value, dict) or set(value) - {"remove", "phantom"}:
            raise ValueError(f"options['sign_props'] must be a dict with keys 'remove' and 'phantom' "
                             f"(a stop sign's index or None), got {value!r}")
        remove, phantom = (self._index(value.get(key), key) for key in ("remove", "phantom"))
        for k, (body, home) in enumerate(self._signs):
            model.body_pos[body] = _PARKED + home if k == remove else home
        self._removed = remove
        self._placed = phantom
        if phantom < 0:
            model.body_pos[self._phantom] = _PARKED
            return
        from racf.sim.world.stop_signs import stop_signs

        sign = stop_signs()[phantom]
        # The panel reaches away from the lane: from the plate's edge nearest it, outwards; and the whole
        # picture stands half a plate out from the sign's pole, so the panel's nearest edge (it stands on
        # the floor, where a sign's plate is on a pole) is where the pole is: a car that passes the sign
        # passes it. (At the plate's edge, 5 cm nearer, a supervised car that stopped in sign 2's bend and
        # pulled off grazed it, 7 mm off the line a car that never stopped drove.)
        s, _ = sign.path.project(np.asarray(sign.position))
        lane_x, lane_y, _ = sign.path.pose_at(s)
        outward = np.array([sign.position[0] - lane_x, sign.position[1] - lane_y])
        across = np.array([-math.sin(sign.face_yaw), math.cos(sign.face_yaw)])  # the plate's local +y
        side = 1.0 if float(outward @ across) >= 0 else -1.0
        x, y = np.asarray(sign.position, float) + side * PLATE_HALF_M * across
        model.body_pos[self._phantom] = (x, y, 0.0)
        model.body_quat[self._phantom] = (math.cos(sign.face_yaw / 2), 0.0, 0.0, math.sin(sign.face_yaw / 2))
        model.geom_pos[self._panel][1] = side * (PHANTOM_PANEL_M[0] / 2 - PLATE_HALF_M)

    def _index(self, value: Any, key: str) -> int:
        if value is None:
            return -1
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value < len(self._signs):
            raise ValueError(f"options['sign_props'][{key!r}] must be a stop sign's index 0..{len(self._signs) - 1} "
                             f"or None, got {value!r}")
        return int(value)

    def info(self, substep: int) -> dict[str, Any]:
        return {"sign_removed": self._removed, "phantom_at": self._placed}

    def owner_of(self, root_body: int) -> str | None:
        return "phantom" if root_body == self._phantom else None
