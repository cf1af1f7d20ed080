"""Stale maps: the stop sign the car meets is not the one its map lists.

The car is briefed with the map (its mission's targets); the world may differ. One scenario,
``stale_map``, with its ``case``:

- ``mapped``: the sign stands where the map says (the control);
- ``moved``: the sign stands ``shift_m`` further along the lane than the map says (negative:
  nearer). The map's entry is stale, the sign is real: the car must stop at the sign it
  sees, and the referee scores it at the real sign's line (a sign moved with its line);
- ``removed``: the map lists the sign, nothing stands there: a stop is needless;
- ``temporary``: a real sign the map does not list: the car must find it for itself;
- ``phantom``: no sign, and the map lists none; a stop sign's picture on a wall panel stands
  where the sign would (``racf.sim.env.sign_props``): a stop is needless.

The attacks act as in any sign approach: a sticker on a real sign, up from the start, is
``physical_patch`` with ``from_start``. ``stale_map`` scores the ``existence`` metric
(``sign_stands``, ``needless_stop``) beside the outcome.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from racf.experiments.scenarios.base import Param, Scenario
from racf.sim.env.sign_props import SignPropsManager

__all__ = ["StaleMap", "CASES", "NO_SIGN_CASES"]

#: The cases, in the order tables show them.
CASES = ("mapped", "moved", "removed", "temporary", "phantom")
#: The cases where no real sign stands at the target: any stop there is needless.
NO_SIGN_CASES = ("removed", "phantom")


class StaleMap(Scenario):
    """A stop-sign approach where the car's map may be wrong about the sign (``case``)."""

    name = "stale_map"
    meaning = "a stop-sign approach against a stale map: the sign moved, removed, temporary, or a phantom picture"
    target = "sign"
    params = (
        Param("case", "mapped", choices=CASES, meaning="what stands where the map lists the sign (see the docs)"),
        Param("shift_m", 1.0, -1.5, 1.5, unit="m",
              meaning="moved: how far further along the lane the sign stands than the map says"),
    )
    metrics = ("existence",)

    def world(self, spec: Any, values: dict[str, Any]) -> tuple:
        return (SignPropsManager(),)

    def check(self, spec: Any, values: dict[str, Any]) -> None:
        if values["case"] == "moved" and abs(values["shift_m"]) < 0.1:
            raise ValueError(f"scenario 'stale_map' case 'moved' needs |shift_m| >= 0.1 m, got {values['shift_m']!r}")

    def plan(self, spec, values, draft):
        case, index = values["case"], spec.sign
        props = {"remove": index if case in NO_SIGN_CASES else None, "phantom": index if case == "phantom" else None}
        options = {**draft.reset_options, "sign_props": props}
        mission = draft.mission
        (target,) = mission.targets
        if case in ("temporary", "phantom"):
            target = replace(target, mapped=False)
        elif case == "moved":
            target = _listed_at(target, mission.path, -values["shift_m"])
        return self.replace(draft, reset_options=options, mission=replace(mission, targets=(target,)))


def _listed_at(target, path, offset_m: float):
    """``target`` as a map lists it ``offset_m`` along ``path`` from where it stands (its pole, its
    stop line and where the path passes it, all moved along the lane)."""
    sign = target.target
    s_sign, _ = path.project(np.asarray(sign.position))
    x0, y0, _ = path.pose_at(s_sign)
    x1, y1, _ = path.pose_at(s_sign + offset_m)
    dx, dy = x1 - x0, y1 - y0
    moved = replace(sign, position=(sign.position[0] + dx, sign.position[1] + dy),
                    stop_line=(sign.stop_line[0] + dx, sign.stop_line[1] + dy), stop_s=sign.stop_s + offset_m)
    return replace(target, target=moved, stop_s=target.stop_s + offset_m, target_s=target.target_s + offset_m)
