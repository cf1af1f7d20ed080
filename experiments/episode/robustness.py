"""The stop rule as signal temporal logic, and its robustness over an episode's step log.

Per target (a ``slot`` of the log), over its approach (from the slot's first step to the car's
first rest after it has moved, and on while it stays at rest; after a stop the car may lawfully
go on):

    always (gap >= 0)  and  always ((gap <= W) -> eventually[0:T] (speed <= V))

``gap`` is the front bumper's distance before the stop line (m; negative past it), ``speed`` the
car's speed (m/s), W = 0.60 m the protocol's success band (the braking window), T = 3 s and
V = 0.05 m/s the protocol's rest speed. In words: the car never crosses the line, and once its
bumper is within the braking window it is at rest within T seconds.

The robustness is computed by rtamt (the maintained STL monitor of the field, discrete-time
offline semantics at the log's 50 Hz). It is signed: negative is a violation, and its size says
by how much. The line clause reads in metres (how far the bumper stayed before the line, or went
past it); the rest clause's speed margin is scaled by ``REST_SCALE_S`` (20 s) into metres too, so
that a car at rest (margin 1 m) never hides how close it came to the line (at most 0.60 m
inside the window). An episode's robustness is the lowest over its targets.

Old logs can be rescored: nothing here reads the simulator.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from racf.experiments.episode.scoring import AT_REST_MPS, SUCCESS_BAND_M

__all__ = ["STOP_RULE", "robustness", "target_robustness", "WINDOW_M", "REST_WITHIN_S", "REST_SCALE_S"]

#: The braking window: the bumper this close to the line, m (the protocol's success band).
WINDOW_M = SUCCESS_BAND_M[1]
#: Once in the window the car is at rest within this, s.
REST_WITHIN_S = 3.0
#: The rest clause's speed margin (m/s) times this reads in metres.
REST_SCALE_S = 20.0
_STEPS_PER_S = 50  # the log's rate: rtamt counts discrete time in samples
#: The stop rule as rtamt reads it (``rest`` is REST_SCALE_S * (V - speed), in metres).
STOP_RULE = (f"always(gap >= 0) and always((gap <= {WINDOW_M}) -> "
             f"eventually[0:{int(REST_WITHIN_S * _STEPS_PER_S)}](rest >= 0))")


def _approach(steps: pd.DataFrame) -> pd.DataFrame:
    """The slot's steps until the car moves off again after its first rest (all of them if it never
    rests or never moves off). The rest itself stays in: cut at its first step, the rule's
    eventually would see only a speed just under the threshold, and the robustness of every stop
    inside the window would be that noise instead of its gap."""
    speed = np.abs(steps["speed"].to_numpy(float))
    moving = speed >= AT_REST_MPS
    moved = np.maximum.accumulate(moving)
    rest = np.flatnonzero(moved & ~moving)
    if not rest.size:
        return steps
    off = np.flatnonzero(moving[rest[0]:])
    return steps.iloc[: rest[0] + off[0]] if off.size else steps


def target_robustness(steps: pd.DataFrame) -> float:
    """The stop rule's robustness over one target's steps (``t``, ``speed``, ``dist_to_stop_line``),
    m; NaN when the target has no stop line (a crate) or no steps."""
    import rtamt

    approach = _approach(steps)
    gap = approach["dist_to_stop_line"].to_numpy(float)
    if not len(gap) or not np.isfinite(gap).all():
        return math.nan
    rest = REST_SCALE_S * (AT_REST_MPS - np.abs(approach["speed"].to_numpy(float)))
    spec = rtamt.StlDiscreteTimeOfflineSpecification()
    spec.declare_var("gap", "float")
    spec.declare_var("rest", "float")
    spec.spec = STOP_RULE
    spec.parse()
    # rtamt counts discrete time in samples: one per 50 Hz step.
    values = spec.evaluate({"time": list(range(len(gap))), "gap": gap.tolist(), "rest": rest.tolist()})
    return float(values[0][1])


def robustness(log: pd.DataFrame) -> float:
    """An episode's robustness: the lowest over its targets (NaN when none has a stop line)."""
    missing = [c for c in ("t", "slot", "speed", "dist_to_stop_line") if c not in log]
    if missing:
        raise ValueError(f"the log lacks column(s) {missing} the stop rule reads")
    values = [target_robustness(steps) for _, steps in log.groupby("slot", sort=True)]
    finite = [v for v in values if math.isfinite(v)]
    return min(finite) if finite else math.nan
