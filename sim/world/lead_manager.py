"""The car ahead's world manager: the lead car of ``racf.sim.world.lead`` driven in MuJoCo.

The lead-vehicle scenario brings it (``world``); it reads the reset option ``lead`` (a
``LeadCar.to_options()`` dict, or None: no lead this episode, parked out of sight) and logs its own
ground truth: the lead's pose and speed (``lead_x``, ``lead_y``, ``lead_yaw``, ``lead_speed``).
Its body is a QCar 2's, built the way cross-traffic's are (``traffic_xml``), named ``lead_0``; a
contact with it is ``lead``. With the option's ``broadcast`` true the lead broadcasts its own state as
fleet vehicle :data:`LEAD_SENDER` (``racf.sim.radio``): its pose, speed, acceleration and brake.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from racf.sim.radio.message import Broadcast
from racf.sim.world.lead import LeadCar
from racf.sim.world.manager import TruthColumn, WorldManager, WorldTarget
from racf.sim.world.qcar2_body import QCar2Body

__all__ = ["LeadManager", "LEAD_PREFIX", "LEAD_COLUMNS", "LEAD_SENDER"]

#: The lead's body and geom names start with this.
LEAD_PREFIX = "lead"
#: Its ground-truth columns: (field, unit, meaning).
LEAD_COLUMNS = (("x", "m", "position, map frame"), ("y", "m", "position, map frame"),
                ("yaw", "rad", "heading, map frame"), ("speed", "m/s", "speed"))
#: The lead's id in the fleet when it broadcasts (its key's: ``racf.sim.radio.keys``).
LEAD_SENDER = 1
#: Its brake counts as on below this acceleration, m/s^2.
_BRAKING_MPS2 = -0.1


class LeadManager(WorldManager):
    """One lead car on the ego car's lane, tabulated at each reset for the whole episode."""

    name = "lead"
    option = "lead"

    def __init__(self) -> None:
        self.car = QCar2Body(LEAD_PREFIX)
        self._lead: LeadCar | None = None
        self._table = np.full((1, 4), math.nan)
        self._broadcast = False
        self._dt = 0.002

    def scene_xml(self) -> str:
        return self.car.xml()

    def bind(self, model: mujoco.MjModel) -> None:
        self.car.bind(model)

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        value = None if value is None else dict(value)
        self._broadcast = value.pop("broadcast", False) if value is not None else False
        if not isinstance(self._broadcast, bool):
            raise ValueError(f"options['lead']['broadcast'] must be true or false, got {self._broadcast!r}")
        self._lead = None if value is None else LeadCar.from_options(value)
        self._dt = physics_dt_s
        if self._lead is None:
            self._table = np.full((1, 4), math.nan)
        else:
            steps = np.arange(int(round(max_episode_s / physics_dt_s)) + 2)
            self._table = self._lead.states(steps * physics_dt_s)
            self.car.paint(model, self._lead.colour)
        self.before_physics(data, 0)

    @property
    def lead(self) -> LeadCar | None:
        return self._lead

    @property
    def body(self) -> int:
        """The lead's body id in the model."""
        return self.car.body

    @property
    def moving(self) -> bool:
        return self._lead is not None

    def state(self, substep: int) -> np.ndarray:
        """(4,) x, y, yaw, speed of the lead at physics step ``substep`` (NaN: no lead)."""
        return self._table[min(substep, len(self._table) - 1)].copy()

    def before_physics(self, data, substep) -> None:
        if self._lead is None:
            self.car.park(data)
            return
        x, y, yaw, _ = self.state(substep)
        self.car.place(data, x, y, yaw)

    def columns(self) -> tuple[TruthColumn, ...]:
        return tuple(TruthColumn(f"lead_{field}", unit, f"ground truth: the lead car's {meaning} (NaN: no lead)")
                     for field, unit, meaning in LEAD_COLUMNS)

    def targets(self) -> tuple[WorldTarget, ...]:
        return (self.car.target((f"{LEAD_PREFIX}_x", f"{LEAD_PREFIX}_y", f"{LEAD_PREFIX}_yaw")),)

    def info(self, substep: int) -> dict[str, Any]:
        return {f"lead_{field}": float(v) for (field, _, _), v in zip(LEAD_COLUMNS, self.state(substep))}

    def owner_of(self, root_body: int) -> str | None:
        return LEAD_PREFIX if self.car.owns(root_body) else None

    def broadcasts(self, substep: int) -> tuple[Broadcast, ...]:
        if self._lead is None or not self._broadcast:
            return ()
        x, y, yaw, speed = self.state(substep)
        before, after = self.state(max(substep - 1, 0))[3], self.state(substep + 1)[3]
        accel = (after - before) / (self._dt * (2 if substep > 0 else 1))
        return (Broadcast(LEAD_SENDER, float(x), float(y), float(yaw), float(speed), float(accel),
                          bool(accel < _BRAKING_MPS2)),)
