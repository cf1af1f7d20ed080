"""Cross-traffic's world manager: the other cars of ``racf.sim.world.traffic`` driven in MuJoCo.

The env knows nothing of it: the cross-traffic scenario brings it (``world``), it reads the reset
option ``traffic`` and logs its own ground-truth columns (each car's pose and speed, and the
conflict point they cross).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

import mujoco
import numpy as np

from racf.sim.world.manager import QCAR2_BOX_M, TruthColumn, WorldManager, WorldTarget
from racf.sim.world.traffic import MAX_TRAFFIC_CARS, TRAFFIC_COLOURS, TrafficCar

__all__ = ["TrafficManager", "traffic_option", "traffic_body", "traffic_paint_geoms", "traffic_xml",
           "TRAFFIC_GEOM_GROUP", "PARKED_Z_M"]

#: Geom group of the other cars: seen by the camera and the LiDARs (groups 0-2), unlike the ego car's.
TRAFFIC_GEOM_GROUP = 2
#: Where an other car the episode does not use waits: below the floor, out of every sensor's sight.
PARKED_Z_M = -5.0
#: The other cars' geoms that carry their colour.
_PAINTED = ("shell", "chassis")
#: Elements of the car's body that an other car leaves out: it is kinematic (a mocap body) and
#: carries no sensors.
_NOT_IN_TRAFFIC = {"freejoint", "joint", "inertial", "camera", "site"}

_STATE = (("x", "m", "position, map frame"), ("y", "m", "position, map frame"),
          ("yaw", "rad", "heading, map frame"), ("speed", "m/s", "speed"))


def traffic_option(cars, conflict_xy: tuple[float, float] | None = None) -> dict:
    """The reset option ``traffic`` for these cars (``TrafficCar``), with the conflict point they
    cross (logged as ground truth; None: none)."""
    return {"cars": [car.to_options() for car in cars],
            "conflict_xy": None if conflict_xy is None else [float(conflict_xy[0]), float(conflict_xy[1])]}


class TrafficManager(WorldManager):
    """Other cars crossing the ego car's path (``racf.sim.world.traffic``): the model holds
    ``cars`` of them, and the reset option ``traffic`` (:func:`traffic_option`: the cars'
    ``TrafficCar.to_options()`` dicts and the conflict point; a plain list of cars is read too)
    drives as many; the rest wait parked out of every sensor's sight. Each car's state at every
    physics step of an episode is tabulated at the reset (they read no one).

    Ground truth: ``traffic`` ((n, 4) x, y, yaw, speed of each driven car) and the log columns
    ``traffic{k}_{x,y,yaw,speed}`` for k < ``MAX_TRAFFIC_CARS`` (NaN for a slot no car fills) and
    ``conflict_x``/``conflict_y``.
    """

    name = "traffic"
    option = "traffic"

    def __init__(self, cars: int) -> None:
        if not (isinstance(cars, int) and not isinstance(cars, bool) and 0 <= cars <= MAX_TRAFFIC_CARS):
            raise ValueError(f"cars must be an int in 0..{MAX_TRAFFIC_CARS}, got {cars!r}")
        self.cars = cars
        self._mocap: list[int] = []
        self._paint: list[list[int]] = []
        self._of_body: dict[int, int] = {}
        self._driven: tuple = ()
        self._conflict = (math.nan, math.nan)
        self._table = np.empty((0, 1, 4))

    def key(self) -> tuple:
        return (self.cars,)

    def scene_xml(self) -> str:
        from racf.sim.world.scene import car_xml

        car = car_xml()
        return "".join(traffic_xml(k, car) for k in range(self.cars))

    def bind(self, model: mujoco.MjModel) -> None:
        self._mocap = [int(model.body_mocapid[model.body(traffic_body(k)).id]) for k in range(self.cars)]
        self._paint = [[model.geom(g).id for g in traffic_paint_geoms(k)] for k in range(self.cars)]
        self._of_body = {model.body(traffic_body(k)).id: k for k in range(self.cars)}

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        cars, conflict = _parsed(value)
        if len(cars) > self.cars:
            raise ValueError(f"options['traffic'] lists {len(cars)} cars; this env holds {self.cars} "
                             f"(make it with world=(TrafficManager({len(cars)}),))")
        self._driven = tuple(TrafficCar.from_options(car) for car in cars)
        self._conflict = conflict
        steps = np.arange(int(round(max_episode_s / physics_dt_s)) + 2)
        self._table = np.stack([car.states(steps * physics_dt_s) for car in self._driven]) \
            if self._driven else np.empty((0, len(steps), 4))
        for k, paint in enumerate(self._paint):
            if k < len(self._driven):
                model.geom_rgba[paint] = TRAFFIC_COLOURS[self._driven[k].colour]
        self.before_physics(data, 0)

    @property
    def moving(self) -> bool:
        return bool(self._driven)

    def before_physics(self, data, substep) -> None:
        """Puts every other car where its lane follower has it at physics step ``substep`` (unused ones stay parked)."""
        for k, mocap in enumerate(self._mocap):
            if k < len(self._driven):
                x, y, yaw, _ = self._table[k, min(substep, self._table.shape[1] - 1)]
                data.mocap_pos[mocap] = (x, y, 0.0)
                data.mocap_quat[mocap] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
            else:
                data.mocap_pos[mocap] = (0.0, 0.0, PARKED_Z_M)
                data.mocap_quat[mocap] = (1.0, 0.0, 0.0, 0.0)

    def states(self, substep: int) -> np.ndarray:
        """(n, 4) x, y, yaw, speed of each driven other car at physics step ``substep``."""
        return self._table[:, min(substep, self._table.shape[1] - 1)].copy()

    def columns(self) -> tuple[TruthColumn, ...]:
        return (TruthColumn("conflict_x", "m", "the conflict point where cross-traffic meets the route, map frame "
                                               "(NaN: none given)"),
                TruthColumn("conflict_y", "m", "the conflict point, map frame (NaN: none given)"),
                *(TruthColumn(f"traffic{k}_{field}", unit, f"ground truth: other car {k}'s {meaning} (NaN: no such car)")
                  for k in range(MAX_TRAFFIC_CARS) for field, unit, meaning in _STATE))

    def info(self, substep: int) -> dict[str, Any]:
        states = self.states(substep)
        out: dict[str, Any] = {"traffic": states, "conflict_x": self._conflict[0], "conflict_y": self._conflict[1]}
        for k in range(MAX_TRAFFIC_CARS):
            values = states[k] if k < len(states) else (math.nan,) * 4
            out.update({f"traffic{k}_{field}": float(v) for (field, _, _), v in zip(_STATE, values)})
        return out

    def targets(self) -> tuple[WorldTarget, ...]:
        """Each crossing car, a vehicle the car may perceive (named as a contact with it is)."""
        return tuple(WorldTarget(f"traffic{k}", "vehicle", traffic_body(k),
                                 (f"traffic{k}_x", f"traffic{k}_y", f"traffic{k}_yaw"), QCAR2_BOX_M)
                     for k in range(self.cars))

    def owner_of(self, root_body: int) -> str | None:
        return f"traffic{self._of_body[root_body]}" if root_body in self._of_body else None


def _parsed(value: Any) -> tuple[list, tuple[float, float]]:
    """The cars and the conflict point of the reset option (None: no cars, no point)."""
    conflict = (math.nan, math.nan)
    if isinstance(value, dict):
        if set(value) - {"cars", "conflict_xy"}:
            raise ValueError(f"options['traffic'] must be a list of other cars (dicts), or a dict with 'cars' and "
                             f"'conflict_xy', got {value!r}")
        point = value.get("conflict_xy")
        if point is not None:
            if not (hasattr(point, "__len__") and len(point) == 2):
                raise ValueError(f"options['traffic']['conflict_xy'] must be (x, y) m or None, got {point!r}")
            conflict = (float(point[0]), float(point[1]))
        value = value.get("cars")
    raw = () if value is None else value
    if isinstance(raw, (str, bytes, dict)) or not hasattr(raw, "__len__"):
        raise ValueError(f"options['traffic'] must be a list of other cars (dicts), got {raw!r}")
    return list(raw), conflict


def traffic_body(index: int, prefix: str = "traffic") -> str:
    """Name of other car ``index``'s (mocap) body (``prefix``: whose cars, for another manager's)."""
    return f"{prefix}_{index}"


def traffic_paint_geoms(index: int, prefix: str = "traffic") -> tuple[str, ...]:
    """Names of other car ``index``'s geoms that carry its colour."""
    return tuple(f"{prefix}_{index}_{name}" for name in _PAINTED)


def traffic_xml(index: int, car_xml: bytes, prefix: str = "traffic") -> str:
    """Other car ``index``: the QCar 2's own bodies and geoms (from its MJCF), welded to one mocap
    body, renamed, in a group every sensor sees, colliding with the ego car's chassis only."""
    root = ET.fromstring(car_xml)
    body = next(b for b in root.iter("body") if b.get("name") == "qcar")
    body = ET.fromstring(ET.tostring(body))  # a copy to edit

    def strip(element: ET.Element) -> None:
        for child in list(element):
            if child.tag in _NOT_IN_TRAFFIC:
                element.remove(child)
            else:
                strip(child)
        if element.get("name"):
            element.set("name", f"{prefix}_{index}_{element.get('name')}")
        if element.tag == "geom":
            # Contact bits: type 4 (no other car, wheel or floor has it in its affinity), affinity 2
            # (the ego chassis's type): a crash with the ego car registers, nothing else costs a contact.
            element.set("group", str(TRAFFIC_GEOM_GROUP))
            if element.get("class") != "qcar_visual":
                element.set("contype", "4")
                element.set("conaffinity", "2")
    strip(body)
    body.set("name", traffic_body(index, prefix))
    body.set("mocap", "true")
    body.set("pos", f"0 0 {PARKED_Z_M}")
    return "\n    " + ET.tostring(body, encoding="unicode")
