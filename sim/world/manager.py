"""World managers: things in the world the env runs without knowing what they are.

A scenario brings its world as managers (MetaDrive's managers, CARLA's scenario actors): bodies
it adds to the model when the env is built, and hooks the env calls at each reset and before
each physics step. The env owns the physics, the sensors and the ego car; a manager owns its
bodies, the reset option it reads and the ground-truth columns it logs (:meth:`WorldManager.columns`).
Cross-traffic is one (``racf.sim.world.traffic_manager``); a user's scenario adds its own through
the env setting ``world`` (``gym.make(ENV_ID, world=(m,))``).

A manager is ground truth: the car's side never reads one; the env puts what a manager reports
into ``info`` (for the referee and the logs) only. The referee logs each declared column from
``info`` without knowing whose it is.

Hooks, in the order the env calls them:

=============================  ================================================================
``scene_xml()``                once, when the env builds its model: MJCF added to the worldbody
``bind(model)``                once, after the build: look up the ids of the bodies added
``reset(model, data, value,    at each reset, after the physics state is cleared and before the
physics_dt_s, max_episode_s)`` ego car is placed (``value``: the reset option ``option``, or None)
``before_physics(data, k)``    before every physics step ``k`` while :attr:`moving` is true
``info(k)``                    after each step: ground truth for ``info`` (the columns' values)
``owner_of(root_body)``        when the car touches something: the name of what it hit, if this
                               manager's
``broadcasts(k)``              after each control step: what its vehicles broadcast of themselves now
                               (``racf.sim.radio``; the env's radio sends it at the radio's rate)
=============================  ================================================================

A manager also declares the bodies it adds that the car may perceive (:meth:`WorldManager.targets`:
a :class:`WorldTarget` each, with its kind, body, truth columns and size). The attacks on a kind
of target (``AttackWrapper.acts_on``), the referee's truth for it and the viewers find it through
that declaration, never through a manager's or an option's name; the preflight checks, before any
simulator is built, that a scenario whose episodes an attack acts on declares a target it can act on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import mujoco

__all__ = ["WorldManager", "TruthColumn", "WorldTarget", "TARGET_KINDS", "QCAR2_BOX_M", "world_targets"]

#: The kinds of thing a declared target is: what an attack on one aims at.
TARGET_KINDS = ("vehicle", "sign", "obstacle", "person")
#: A QCar 2's body as its collision box: length, width, height, m (the other cars' bodies are the
#: ego car's MJCF; every footprint, box and gap racf draws or measures reads it from one place,
#: :data:`racf.vehicle.QCAR2_BOX_M`, which the car's software shares).
from racf.vehicle import QCAR2_BOX_M  # noqa: E402


@dataclass(frozen=True)
class TruthColumn:
    """One ground-truth column a world manager logs (a step log column on the referee's side).

    Attributes:
        name: the column (an ``info`` key the manager's :meth:`WorldManager.info` fills with a number,
            a bool or a string at every step).
        unit: SI unit (``m``, ``s``, ``rad``, ``m/s``), ``bool``, ``1`` or ``""``.
        meaning: what it holds, one line.
    """

    name: str
    unit: str
    meaning: str


@dataclass(frozen=True)
class WorldTarget:
    """A body a world manager adds that the car may perceive (and an attacker may aim at).

    Attributes:
        name: what it is called (in messages, and as the prefix of its truth columns).
        kind: one of :data:`TARGET_KINDS`.
        body: its MuJoCo body's name (the model's, once the env is built).
        pose_columns: the manager's truth columns that hold its x, y (m) and yaw (rad) in the map frame
            (NaN: not in the world this episode).
        size_m: its box, length, width and height, m, centred over its pose (a QCar 2's:
            :data:`QCAR2_BOX_M`).
    """

    name: str
    kind: str
    body: str
    pose_columns: tuple[str, str, str]
    size_m: tuple[float, float, float]

    def __post_init__(self) -> None:
        if self.kind not in TARGET_KINDS:
            raise ValueError(f"target {self.name!r}: kind must be one of {TARGET_KINDS}, got {self.kind!r}")
        if len(self.pose_columns) != 3 or len(self.size_m) != 3:
            raise ValueError(f"target {self.name!r}: pose_columns names x, y, yaw and size_m is length, width, height")

    def pose(self, truth: dict) -> tuple[float, float, float] | None:
        """Its pose from a step's ground truth (``info``, a log row), None while it is not in the world."""
        x, y, yaw = (float(truth.get(column, math.nan)) for column in self.pose_columns)
        return None if not math.isfinite(x) else (x, y, yaw)


def world_targets(managers, kind: str | None = None) -> tuple[WorldTarget, ...]:
    """The targets ``managers`` declare, in their order (of ``kind`` only, when given)."""
    return tuple(t for m in managers for t in m.targets() if kind is None or t.kind == kind)


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

    def columns(self) -> tuple[TruthColumn, ...]:
        """The ground-truth columns this manager logs: :meth:`info` gives each a value at every step,
        and the referee writes them into the step log (the car never sees them)."""
        return ()

    def targets(self) -> tuple[WorldTarget, ...]:
        """The bodies this manager adds that the car may perceive (known before the env is built: the
        preflight reads them). Each one's pose columns are among :meth:`columns`."""
        return ()

    def info(self, substep: int) -> dict[str, Any]:
        """Ground truth for ``info`` at physics step ``substep`` (every declared column among it)."""
        return {}

    def owner_of(self, root_body: int) -> str | None:
        """The name of what a contact with ``root_body`` hit, when it is this manager's (else None)."""
        return None

    def broadcasts(self, substep: int) -> tuple:
        """What this manager's vehicles broadcast of themselves at physics step ``substep``
        (``racf.sim.radio.Broadcast`` each; none: they broadcast nothing)."""
        return ()
