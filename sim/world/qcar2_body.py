"""Another QCar 2 in the world, in one call: what a scenario's world manager needs to add a car.

``QCar2Body(name)`` is the ego car's own bodies and geoms (from its MJCF) welded to one mocap body,
renamed ``name_0``, in a group every sensor sees, colliding with the ego car's chassis only (the
way cross-traffic's cars and the car ahead are built). A world manager returns :meth:`QCar2Body.xml`
from ``scene_xml()``, calls :meth:`~QCar2Body.bind` from ``bind()``, moves it with
:meth:`~QCar2Body.place` (or parks it out of sight with :meth:`~QCar2Body.park`) each physics step,
answers ``owner_of()`` with :meth:`~QCar2Body.owns`, and declares it with :meth:`~QCar2Body.target`
so the attacks on a vehicle, the referee and the viewers find it.

Example:
    >>> from racf.sim.world.qcar2_body import QCar2Body
    >>> car = QCar2Body("cutin")
    >>> car.target(("cutin_x", "cutin_y", "cutin_yaw")).kind, car.body_name
    ('vehicle', 'cutin_0')
"""

from __future__ import annotations

import math

import mujoco

from racf.sim.world.manager import QCAR2_BOX_M, WorldTarget
from racf.sim.world.traffic import TRAFFIC_COLOURS
from racf.sim.world.traffic_manager import PARKED_Z_M, traffic_body, traffic_paint_geoms, traffic_xml

__all__ = ["QCar2Body"]


class QCar2Body:
    """One other QCar 2, kinematic (a mocap body: it goes where it is placed).

    Args:
        name: its name: the prefix of its body and geoms (``name_0``), and what a contact with it is called.
    """

    def __init__(self, name: str) -> None:
        if not name.isidentifier():
            raise ValueError(f"a car's name must be an identifier (it names MJCF bodies), got {name!r}")
        self.name = name
        self.body_name = traffic_body(0, name)
        self._body = self._mocap = -1
        self._paint: list[int] = []

    def xml(self) -> str:
        """Its MJCF, for the manager's ``scene_xml()``."""
        from racf.sim.world.scene import car_xml

        return traffic_xml(0, car_xml(), self.name)

    def bind(self, model: mujoco.MjModel) -> None:
        """Looks up its ids in the built model (the manager's ``bind()``)."""
        self._body = model.body(self.body_name).id
        self._mocap = int(model.body_mocapid[self._body])
        self._paint = [model.geom(g).id for g in traffic_paint_geoms(0, self.name)]

    @property
    def body(self) -> int:
        """Its body id in the model."""
        return self._body

    def paint(self, model: mujoco.MjModel, colour: str) -> None:
        """Paints it one of ``TRAFFIC_COLOURS`` (red, blue, yellow, white)."""
        if colour not in TRAFFIC_COLOURS:
            raise ValueError(f"colour must be one of {tuple(TRAFFIC_COLOURS)}, got {colour!r}")
        model.geom_rgba[self._paint] = TRAFFIC_COLOURS[colour]

    def place(self, data: mujoco.MjData, x: float, y: float, yaw: float) -> None:
        """Puts its body origin (midway between its axles) at (x, y), heading ``yaw`` (map frame)."""
        data.mocap_pos[self._mocap] = (x, y, 0.0)
        data.mocap_quat[self._mocap] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))

    def park(self, data: mujoco.MjData) -> None:
        """Takes it out of the world (below the floor, out of every sensor's sight)."""
        data.mocap_pos[self._mocap] = (0.0, 0.0, PARKED_Z_M)
        data.mocap_quat[self._mocap] = (1.0, 0.0, 0.0, 0.0)

    def owns(self, root_body: int) -> bool:
        """Whether a contact with ``root_body`` is a contact with this car."""
        return root_body == self._body

    def target(self, pose_columns: tuple[str, str, str]) -> WorldTarget:
        """Its declaration as a vehicle the car may perceive, with the manager's truth columns of its pose."""
        return WorldTarget(self.name, "vehicle", self.body_name, tuple(pose_columns), QCAR2_BOX_M)
