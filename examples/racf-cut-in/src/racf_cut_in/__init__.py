"""A car cuts in: an example racf scenario written against racf's docs, with no edit to racf.

A second QCar 2 drives in the lane beside the ego car's (``lateral_m`` to its left), ``ahead_m``
ahead, slower than the ego car; at ``merge_t`` it merges into the ego car's lane over ``merge_s``,
then at ``brake_t`` brakes at ``decel`` to a stop (never past the sign's line). Everything the
scenario is lives here:

- its world, :class:`CutInCar`: the car is one :class:`~racf.sim.world.qcar2_body.QCar2Body`, moved
  every physics step along the trajectory the plan tabulated, logging its own ground truth
  (``cutin_x``, ``cutin_y``, ``cutin_yaw``, ``cutin_speed``) and declared as a ``vehicle`` target:
  racf's attacks on a car ahead (``lead_patch``, ``lead_frustum``, ``lead_hide``, ``lead_phantom``)
  find it through that declaration;
- the car's side: the mission engages racf's ``following`` car stage, which perceives whatever car
  is on the lane ahead;
- its criteria: touching the car that cut in ends the episode (CARLA's vehicle penalty, x 0.60);
  the smallest clear gap to it is measured (informative);
- its end: once the car that cut in is at rest for good and the ego car has stood a second behind it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from racf.experiments.episode.criteria import Criterion, NoContact
from racf.experiments.metrics import Field
from racf.experiments.scenarios import Param, Scenario
from racf.sim.world.manager import QCAR2_BOX_M, TruthColumn, WorldManager
from racf.sim.world.qcar2_body import QCar2Body

__all__ = ["CutIn", "CutInCar", "NoCutInContact", "CutInGap", "trajectory"]

#: The trajectory's table step, s (the manager holds the nearest sample: the physics runs at 500 Hz).
TABLE_DT_S = 0.002
#: The episode's time limit, s.
MAX_EPISODE_S = 16.0
#: The ego car has stood this long behind the stopped car: the episode is over, s.
REST_BEHIND_S = 1.0
_AT_REST_MPS = 0.05
_NAN = math.nan
_COLUMNS = (("cutin_x", "m", "ground truth: the car that cuts in, position, map frame (NaN: none)"),
            ("cutin_y", "m", "ground truth: the car that cuts in, position, map frame (NaN: none)"),
            ("cutin_yaw", "rad", "ground truth: the car that cuts in, heading, map frame"),
            ("cutin_speed", "m/s", "ground truth: the car that cuts in, speed"))


def trajectory(path, start_s: float, stop_s: float, values: dict, horizon_s: float) -> dict:
    """The car's states every ``TABLE_DT_S`` (x, y, yaw, speed), from the ego car's lane ``path``: along
    it from ``start_s`` at ``speed``, braking at ``brake_t`` to a stop no farther than ``stop_s``, and
    across it from ``lateral_m`` left of the centre line to the line between ``merge_t`` and
    ``merge_t + merge_s`` (a smooth cosine step)."""
    t = np.arange(0.0, horizon_s + TABLE_DT_S, TABLE_DT_S)
    v0, a, tb = values["speed"], values["decel"], values["brake_t"]
    braking = np.clip(t - tb, 0.0, v0 / a)
    s = start_s + v0 * np.minimum(t, tb) + v0 * braking - 0.5 * a * braking ** 2
    s = np.minimum(s, stop_s)
    done = np.clip((t - values["merge_t"]) / values["merge_s"], 0.0, 1.0)
    lateral = values["lateral_m"] * 0.5 * (1.0 + np.cos(math.pi * done))
    poses = np.array([path.pose_at(float(si)) for si in s])
    left = np.column_stack([-np.sin(poses[:, 2]), np.cos(poses[:, 2])])
    xy = poses[:, :2] + lateral[:, None] * left
    vel = np.gradient(xy, TABLE_DT_S, axis=0)
    speed = np.hypot(vel[:, 0], vel[:, 1])
    yaw = np.where(speed > 1e-6, np.arctan2(vel[:, 1], vel[:, 0]), poses[:, 2])
    return {"x": xy[:, 0].tolist(), "y": xy[:, 1].tolist(), "yaw": yaw.tolist(), "speed": speed.tolist(),
            "colour": values["colour"]}


class CutInCar(WorldManager):
    """The car that cuts in, following its tabulated trajectory (the reset option ``cutin``; absent:
    parked out of sight)."""

    name = option = "cutin"

    def __init__(self) -> None:
        self.car = QCar2Body("cutin")
        self._table = np.full((1, 4), _NAN)

    def scene_xml(self) -> str:
        return self.car.xml()

    def bind(self, model) -> None:
        self.car.bind(model)

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        self._dt = physics_dt_s
        if value is None:
            self._table = np.full((1, 4), _NAN)
        else:
            self._table = np.column_stack([value["x"], value["y"], value["yaw"], value["speed"]])
            self.car.paint(model, value["colour"])
        self.before_physics(data, 0)

    @property
    def moving(self) -> bool:
        return bool(np.isfinite(self._table[0, 0]))

    def _state(self, substep: int) -> np.ndarray:
        i = min(int(round(substep * self._dt / TABLE_DT_S)), len(self._table) - 1)
        return self._table[i]

    def before_physics(self, data, substep: int) -> None:
        x, y, yaw, _ = self._state(substep)
        if math.isfinite(x):
            self.car.place(data, x, y, yaw)
        else:
            self.car.park(data)

    def columns(self) -> tuple[TruthColumn, ...]:
        return tuple(TruthColumn(*c) for c in _COLUMNS)

    def targets(self):
        return (self.car.target(("cutin_x", "cutin_y", "cutin_yaw")),)

    def info(self, substep: int) -> dict:
        return {name: float(v) for (name, _, _), v in zip(_COLUMNS, self._state(substep))}

    def owner_of(self, root_body: int) -> str | None:
        return "cutin" if self.car.owns(root_body) else None


class NoCutInContact(NoContact):
    """Touch not the car that cut in (CARLA's ``CollisionTest`` against vehicles: x 0.60, and the route ends)."""

    name = "no_cutin_contact"
    checks = "the car never touched the car that cut in"
    penalty = 0.60
    said = ("followed the car that cut in without contact", "touched the car that cut in")

    def guards(self, touched: str) -> bool:
        return touched == "cutin"


class CutInGap(Criterion):
    """The smallest clear gap to the car that cut in, once it is in the lane (informative)."""

    name = "cutin_gap"
    checks = "the clear gap to the car that cut in never closed to 0.1 m"
    optional = True
    fields = (Field("cutin_min_gap_m", _NAN, "m", "the smallest clear gap to the car that cut in, once in the lane",
                    "median"),)
    headline = ("cutin_min_gap_m",)

    def measures(self, episode) -> dict:
        log, merged = episode.log, episode.plan.extras["merged_s"]
        after = log["t"].to_numpy(float) >= merged
        gap = np.hypot(log["cutin_x"] - log["x"], log["cutin_y"] - log["y"]).to_numpy(float) - QCAR2_BOX_M[0]
        return {"cutin_min_gap_m": float(gap[after].min()) if after.any() else _NAN}

    def passed(self, episode) -> bool:
        return not self.measures(episode)["cutin_min_gap_m"] < 0.1


class CutIn(Scenario):
    """A car merges into the ego car's lane from the one beside it at a short gap, then brakes."""

    name = "cut_in"
    meaning = "a car merges into the lane from the next one at a short gap, then brakes to a stop"
    target = "sign"
    params = (
        Param("ahead_m", 1.6, 0.8, 3.0, unit="m", meaning="how far ahead the car that cuts in starts (body to body)"),
        Param("lateral_m", 0.3, 0.2, 0.5, unit="m", meaning="how far left of the ego car's lane it starts"),
        Param("speed", 0.5, 0.2, 1.0, unit="m/s", meaning="its speed"),
        Param("merge_t", 0.5, 0.0, 5.0, unit="s", meaning="when it begins to merge"),
        Param("merge_s", 1.0, 0.3, 3.0, unit="s", meaning="how long its merge takes"),
        Param("brake_t", 3.0, 0.5, 10.0, unit="s", meaning="when it brakes"),
        Param("decel", 2.0, 0.5, 6.0, unit="m/s^2", meaning="how hard it brakes"),
        Param("colour", "blue", choices=("red", "blue", "yellow", "white"), meaning="its paint"),
    )
    criteria = (NoCutInContact, CutInGap)

    def run_up(self, spec):
        from racf.experiments.episode.plan import longest_run_up

        return math.floor(longest_run_up("sign", spec.sign, spec.sign_geometry) * 10) / 10

    def env_settings(self, spec, values) -> dict:
        return {"max_episode_s": MAX_EPISODE_S}

    def world(self, spec, values):
        return (CutInCar(),)

    def plan(self, spec, values, draft):
        mission = draft.mission
        start = draft.start_s_m + values["ahead_m"]
        stop = mission.targets[-1].stop_s - draft.calibration.bumper_x_m  # its bumper on the sign's line
        if start >= stop:
            raise ValueError(f"scenario 'cut_in': ahead_m {values['ahead_m']} leaves it no road before sign "
                             f"{spec.sign}'s line")
        horizon = draft.max_steps * draft.control_dt_s
        table = trajectory(mission.path, start, stop, values, horizon)
        moving = np.flatnonzero(np.asarray(table["speed"]) > 1e-3)
        rest_s = float((moving[-1] + 1) * TABLE_DT_S) if moving.size else 0.0
        options = {**draft.reset_options, "cutin": table}
        # The car drives in traffic: the mission engages racf's following stage.
        stages = (*mission.stages, "following")
        return self.replace(draft, reset_options=options, mission=dataclasses.replace(mission, stages=stages),
                            extras={**draft.extras, "cutin_rest_s": rest_s,
                                    "merged_s": values["merge_t"] + values["merge_s"]})

    def over(self, plan, rows: list[dict]) -> bool:
        """Over once the car that cut in is at rest for good and the ego car has stood behind it."""
        if rows[-1]["t"] < plan.extras["cutin_rest_s"]:
            return False
        stood = round(REST_BEHIND_S / plan.control_dt_s)
        recent = rows[-stood:]
        return len(recent) == stood and all(abs(r["speed"]) < _AT_REST_MPS for r in recent)
