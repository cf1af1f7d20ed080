"""World managers: things in the world the env runs without knowing what they are.

A scenario brings its world as managers (MetaDrive's managers, CARLA's scenario actors): bodies
it adds to the model when the env is built, and hooks the env calls at each reset and before
each physics step. The env owns the physics, the sensors and the ego car; a manager owns its
bodies and the reset option it reads. Cross-traffic is one (:class:`TrafficManager`); a user's
scenario adds its own through the env setting ``world`` (``gym.make(ENV_ID, world=(m,))``).

A manager is ground truth: the car's side never reads one; the env puts what a manager reports
into ``info`` (for the referee and the logs) only.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

__all__ = ["WorldManager", "TrafficManager"]


class WorldManager:
    """One feature of the world, driven by the env (override what the feature needs).

    Attributes:
        name: what it is called in messages.
        option: the ``reset(options=...)`` key it reads (None: it reads none); its value, or
            None when an episode does not give it, reaches :meth:`reset`.
    """

    name = "world"
    option: str | None = None

    def key(self) -> tuple:
        """What makes two managers build the same world (the arguments that change the model):
        envs are reused between episodes whose managers have equal keys."""
        return ()

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other.key() == self.key()

    def __hash__(self) -> int:
        return hash((type(self).__qualname__, self.key()))

    def __repr__(self) -> str:
        return f"{type(self).__name__}{self.key()}"

    def scene_xml(self) -> str:
        """MJCF elements added to the map's ``<worldbody>`` when the env builds its model."""
        return ""

    def bind(self, model: mujoco.MjModel) -> None:
        """Called once the model is built: look up the ids of the bodies this manager added."""

    def reset(self, model: mujoco.MjModel, data: mujoco.MjData, value: Any, physics_dt_s: float,
              max_episode_s: float) -> None:
        """Called at each reset after the physics state is cleared, before the ego car is placed."""

    @property
    def moving(self) -> bool:
        """Whether it moves bodies this episode: the env then calls :meth:`before_physics` every
        physics step (a still world lets the env step physics in strides)."""
        return False

    def before_physics(self, data: mujoco.MjData, substep: int) -> None:
        """Called before physics step ``substep`` (since the reset) while :attr:`moving`."""

    def info(self, substep: int) -> dict[str, Any]:
        """Ground truth for ``info`` at physics step ``substep``."""
        return {}

    def owner_of(self, root_body: int) -> str | None:
        """The name of what a contact with ``root_body`` hit, when it is this manager's (else None)."""
        return None


class TrafficManager(WorldManager):
    """Other cars crossing the ego car's path (``racf.sim.world.traffic``): the model holds
    ``cars`` of them, and the reset option ``traffic`` (a list of ``TrafficCar.to_options()``
    dicts) drives as many; the rest wait parked out of every sensor's sight. Each car's state at
    every physics step of an episode is tabulated at the reset (they read no one)."""

    name = "traffic"
    option = "traffic"

    def __init__(self, cars: int) -> None:
        self.cars = cars
        self._mocap: list[int] = []
        self._paint: list[list[int]] = []
        self._of_body: dict[int, int] = {}
        self._driven: tuple = ()
        self._table = np.empty((0, 1, 4))

    def key(self) -> tuple:
        return (self.cars,)

    def scene_xml(self) -> str:
        from racf.sim.world.scene import ASSETS_DIR, traffic_xml

        car_xml = (ASSETS_DIR / "qcar2.xml").read_bytes()
        return "".join(traffic_xml(k, car_xml) for k in range(self.cars))

    def bind(self, model: mujoco.MjModel) -> None:
        from racf.sim.world.scene import traffic_body, traffic_paint_geoms

        self._mocap = [int(model.body_mocapid[model.body(traffic_body(k)).id]) for k in range(self.cars)]
        self._paint = [[model.geom(g).id for g in traffic_paint_geoms(k)] for k in range(self.cars)]
        self._of_body = {model.body(traffic_body(k)).id: k for k in range(self.cars)}

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        from racf.sim.world.traffic import TRAFFIC_COLOURS, TrafficCar

        raw = () if value is None else value
        if isinstance(raw, (str, bytes, dict)) or not hasattr(raw, "__len__"):
            raise ValueError(f"options['traffic'] must be a list of other cars (dicts), got {raw!r}")
        if len(raw) > self.cars:
            raise ValueError(f"options['traffic'] lists {len(raw)} cars; this env holds {self.cars} "
                             "(make it with traffic_cars=N)")
        self._driven = tuple(TrafficCar.from_options(car) for car in raw)
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
        from racf.sim.world.scene import PARKED_Z_M

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

    def info(self, substep: int) -> dict[str, Any]:
        return {"traffic": self.states(substep)}

    def owner_of(self, root_body: int) -> str | None:
        return f"traffic{self._of_body[root_body]}" if root_body in self._of_body else None
