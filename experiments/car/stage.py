"""A stage of the car: a declared part of its software that a mission engages by name.

The car's own loop (localisation, the stop-sign perception, its defence and braker, the lane
follower: :class:`~racf.experiments.car.software.Car`) runs on every episode. A stage is what a
mission adds beside it: following the car ahead (``following``), an emergency brake for something
upright in the lane (a plug-in's), a supervisor. Each control step the car hands every stage the
same :class:`CarView` (the observation, the car's estimate of itself, the map's lane ahead) and
takes the lowest of their speed caps with its braker's: no stage can raise what another limits.

A stage declares its step-log columns (:attr:`CarStage.columns`, the car's side) and the series a
viewer draws (:attr:`CarStage.series`); it builds its own defence instance from the episode's
(:attr:`StageContext.make_defence`), so its state is its target's. Like the rest of the car it
reads the view and the map only, never ``info``.

Register one under the entry-point group ``racf.car_stages`` (racf's own: ``following``), or in a
``--plugin`` file; a scenario's :meth:`~racf.experiments.scenarios.Scenario.plan` engages it by
putting its name in ``Mission.stages``.

**Supervision is a contract.** A stage that defends a distance to a target publishes what it
believes of it each step as a typed :class:`TargetTrack` (``StageLimit.track``; the class says the
kind in :attr:`CarStage.publishes`), and the car's own loop publishes its sign's in
:attr:`CarView.tracks`. A supervising stage (:mod:`racf.experiments.car.supervisor`) declares the
kind it supervises and reads only that track, never a neighbour's internals; the car's assembly
(:mod:`racf.experiments.car.assembly`) puts one above every published track when the settings ask
for it, and a stage that publishes none cannot be supervised.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar

import numpy as np

from racf.controllers import CameraModel
from racf.sim.world.road_graph import Path

__all__ = ["CarStage", "CarView", "StageColumn", "StageContext", "StageLimit", "TargetTrack", "NO_LIMIT"]


@dataclass(frozen=True)
class StageColumn:
    """One step-log column a stage writes (on the car's side of the log).

    Attributes:
        name: the column's name (it must not be one of racf's own, nor another stage's).
        unit: SI unit, ``bool``, ``1`` (a share) or ``""``.
        meaning: what it holds.
    """

    name: str
    unit: str
    meaning: str


@dataclass(frozen=True)
class StageContext:
    """What a stage is built with, once an episode, before the car starts.

    Attributes:
        camera: the camera's intrinsics.
        camera_xy_m: the camera's place on the body, m.
        camera_height_m: the camera's height above the floor, m.
        lidar_xy_m: the LiDAR's place on the body, m.
        bumper_ahead_of_camera_m: the front bumper's distance ahead of the camera, m.
        make_defence: a fresh instance of the episode's defence (a ``DistanceEstimator``), configured
            with the car's build: a stage that defends a distance gets its own.
        detector: the name of the episode's stop-sign detector.
        target_decel_mps2: the hardest a target of the mission brakes, as its scenario states it, m/s^2
            (None: none stated; the supervisor's a_max).
        target_accel_mps2: the hardest it pulls away, as its scenario states it, m/s^2 (None: none stated).
        fleet_keys: the public keys of the fleet's vehicles the car is provisioned with, by sender id
            (``racf.sim.radio``; empty: it trusts no broadcast).
    """

    camera: CameraModel
    camera_xy_m: tuple[float, float]
    camera_height_m: float
    lidar_xy_m: tuple[float, float]
    bumper_ahead_of_camera_m: float
    make_defence: Callable[[], Any]
    detector: str = "classical"
    target_decel_mps2: float | None = None
    target_accel_mps2: float | None = None
    fleet_keys: dict = field(default_factory=dict)


@dataclass(frozen=True)
class TargetTrack:
    """What a stage believes of its target on one step: all a supervising stage reads of it.

    Distances are the camera's, along its optical axis, to the target's near face (a car's rear, a
    sign's face), m; NaN: none this step.

    Attributes:
        kind: the target's kind (``racf.sim.world.manager.TARGET_KINDS``: sign, obstacle, vehicle, person).
        distance_m: the stage's defended distance (what its own cap acts on).
        cap_mps: the stage's own speed cap, m/s (inf: none).
        moving: the target can move (a vehicle); a static one's world speed is 0.
        speed_mps: the target's speed along the lane as the stage estimates it, m/s (0: static).
        speed_known: the stage's speed estimate is confirmed (its own witnesses, not a default).
        depth_m: the depth camera's distance (NaN: none).
        lidar_m: the LiDAR track's distance (NaN: none).
        size_m: the size witness's distance, from the box and the target's known size (NaN: none).
        map_m: where the map and the car's own pose put it (NaN: the map does not list it).
        stop_at_m: where the car's front must stand short of the target's face, m (a sign: its stop
            line from the map; 0: the face itself, the margin the envelope keeps).
        line_m: the car's own distance along its route from its front bumper to the target's stop line,
            from its pose estimate and the map, m (NaN: the map does not list the target).
        broadcast_m: where the target's own checked broadcast puts it (NaN: none).
        broadcast_mps: its speed as the broadcast tells it, m/s (NaN: none).
        broadcast_trusted: the broadcast has agreed with the stage's distance long enough, and not
            disagreed since.
        detected: the stage's detector found the target on this frame.
        index: which of its targets the publisher means (a new index: another target).
        bearing_rad: the target's bearing from the camera, left positive (NaN: not seen this frame).
    """

    kind: str
    distance_m: float
    cap_mps: float
    moving: bool = False
    speed_mps: float = 0.0
    speed_known: bool = True
    depth_m: float = math.nan
    lidar_m: float = math.nan
    size_m: float = math.nan
    map_m: float = math.nan
    stop_at_m: float = 0.0
    line_m: float = math.nan
    broadcast_m: float = math.nan
    broadcast_mps: float = math.nan
    broadcast_trusted: bool = False
    detected: bool = False
    index: int = 0
    bearing_rad: float = math.nan

    @property
    def ranges(self) -> tuple[float, float]:
        """The range witnesses that measure the target itself: the depth and the LiDAR's track."""
        return self.depth_m, self.lidar_m


@dataclass(frozen=True)
class CarView:
    """What every stage sees on one control step: the observation and the car's own estimates.

    Attributes:
        obs: the observation (``rgb``, ``depth``, ``lidar``, ``state``, ...).
        pose: the car's own pose estimate (x, y m, yaw rad, map frame).
        path: the route's path on the map.
        progress_m: the car's progress along ``path``, m (its rear axle).
        speed_mps: the encoder's speed, m/s.
        yaw_rate_radps: the gyro's yaw rate less the filter's bias estimate, rad/s.
        lateral_mps: the camera's sideways speed (yaw rate x its lever arm), m/s.
        dt: the control period, s.
        frame_new: a new camera frame arrived this step.
        scan_new: a new LiDAR scan arrived this step.
        beam_age_s: each LiDAR beam's age on a new scan, s (None: no new scan).
        tracks: the tracks the car's own loop publishes this step, by kind (its stop sign's).
    """

    obs: dict
    pose: np.ndarray
    path: Path
    progress_m: float
    speed_mps: float
    yaw_rate_radps: float
    lateral_mps: float
    dt: float
    frame_new: bool
    scan_new: bool
    beam_age_s: np.ndarray | None = None
    tracks: dict = field(default_factory=dict)

    @property
    def scan(self) -> np.ndarray | None:
        """The LiDAR's scan on the step it arrives, else None (hand a tracker each scan once)."""
        return self.obs["lidar"] if self.scan_new else None


@dataclass(frozen=True)
class StageLimit:
    """What a stage made of one control step.

    Attributes:
        speed_cap_mps: its limit on the car's speed, m/s (inf: none; 0: stop).
        values: its step-log columns' values, one per declared column.
        detail: anything else it wants kept for viewers (not logged).
        track: what it believes of its target (:class:`TargetTrack`; None: it publishes none).
    """

    speed_cap_mps: float
    values: dict = field(default_factory=dict)
    detail: Any = None
    track: TargetTrack | None = None


#: A stage that limits nothing and logs nothing.
NO_LIMIT = StageLimit(math.inf)


class CarStage:
    """The base of a car stage (a plug-in subclasses it).

    A subclass sets ``name``, declares ``columns``, and implements :meth:`reset` and
    :meth:`step`; :meth:`idle` gives its columns' values before its first step. ``series`` names
    the columns a viewer draws together, with their colours and legends: column -> ((r, g, b),
    legend), all in metres.
    """

    racf_part = "car stage"
    name: ClassVar[str] = ""
    #: The step-log columns it writes every step (declared on the class: the reference pages and the
    #: preflight read them before any episode).
    columns: ClassVar[tuple[StageColumn, ...]] = ()
    #: The columns a viewer draws as this stage's distance series: column -> ((r, g, b), legend).
    series: ClassVar[dict[str, tuple[tuple[int, int, int], str]]] = {}
    #: The kind of target whose :class:`TargetTrack` it publishes in ``StageLimit.track`` (None: none,
    #: and it cannot be supervised).
    publishes: ClassVar[str | None] = None

    def __init__(self, context: StageContext) -> None:
        self.context = context

    def idle(self) -> StageLimit:
        """What the stage says before it has stepped (its columns NaN or False)."""
        return StageLimit(math.inf, {c.name: (False if c.unit == "bool" else math.nan) for c in self.columns})

    def reset(self) -> None:
        """Forgets the last episode."""

    def step(self, view: CarView) -> StageLimit:  # pragma: no cover - the contract
        """One control step on what the car sees; returns its speed cap and its columns' values."""
        raise NotImplementedError
