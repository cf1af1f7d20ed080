"""How the car followed: the gap to the lead, time-to-collision and headway, scored from the step log.

Pure, like cross-traffic's scorer: it reads the referee's columns (the ego car's true pose and
speed, the lead's ``lead_*`` columns, what the car touched) and nothing else.

- **gap**: the clear gap to the lead, m, as the supervisor defines it (one definition,
  :mod:`racf.vehicle`): from the centre of the ego car's front bumper (the car's build) to the centre
  of the lead's rear face. The supervisor keeps its part along the camera's axis, never more.
- **time-to-collision** (TTC): the gap over the closing speed (the ego car's speed less the
  lead's), while they close; the episode's smallest, before any contact (0 at contact with the
  lead; NaN: they never closed).
- **headway**: the gap over the ego car's speed; the time spent with it under ``MIN_HEADWAY_S``
  while the car moves (a headway violation).
- **hard brakes**: the ego car's decelerations past ``HARD_BRAKE_MPS2``, counted once per episode
  of braking;
- **needless hard brakes**: those that begin while the real lead asks for none: its time-to-collision
  over ``NEEDLESS_TTC_S`` (or they do not close), the headway at least ``MIN_HEADWAY_S``, and the lead
  itself not braking hard within the last ``ANSWER_S`` (what a phantom car ahead costs; the catch-up to
  a lead first seen close, or the answer to a lead's own hard brake, are not: at its start the two
  still close slowly, so time-to-collision alone would call it needless).
- **mean time gap**: the headway averaged over the steps the car moves (what a defence's caution
  costs in following distance);
- **time to finish**: when the episode ended, s (the scenario ends it once the lead is at rest for
  good and the car has stood behind it: a car that hangs back finishes later).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np
import pandas as pd

from racf.vehicle import clear_gap_of_poses

__all__ = ["FollowingOutcome", "score_following", "MIN_HEADWAY_S", "HARD_BRAKE_MPS2", "MOVING_MPS", "NEEDLESS_TTC_S",
           "ANSWER_S"]

#: Under this headway the car follows too close, s (half the following controller's 1 s policy:
#: the two-second rule's half, scaled in time, not in size).
MIN_HEADWAY_S = 0.5
#: A deceleration past this is a hard brake, m/s^2 (0.3 g).
HARD_BRAKE_MPS2 = 3.0
#: Headway counts only while the car moves faster than this, m/s.
MOVING_MPS = 0.1
#: A hard brake is needless when it begins with the real time-to-collision over this, s: past where
#: a forward-collision warning sounds (about 2.5 s), nothing real asks for braking at 0.3 g. The
#: catch-up to a lead first seen out of a bend (2 s at 0.4 m/s of closing) is not needless.
NEEDLESS_TTC_S = 3.0
#: A hard brake that begins within this of the lead's own hard brake answers it, s (a driver's
#: reaction, 1 s, with the car's own lag).
ANSWER_S = 1.0


@dataclass(frozen=True)
class FollowingOutcome:
    """One episode's following (NaN/0 without a lead)."""

    lead_collision: bool
    min_gap_m: float
    min_ttc_s: float
    headway_violation_s: float
    hard_brakes: int
    needless_hard_brakes: int = 0
    mean_time_gap_s: float = math.nan
    finish_s: float = math.nan

    def to_dict(self) -> dict:
        return asdict(self)


@lru_cache(maxsize=1)
def _bumper_x_m() -> float:
    """The front bumper's place ahead of the body origin (the car's build, read from its model)."""
    from racf.sim.sensors.calibration import car_build

    return car_build(320, 240).bumper_x_m  # the mounts do not depend on the resolution


def gaps(log: pd.DataFrame) -> np.ndarray:
    """(n,) the clear gap to the lead at each step, m (NaN: no lead)."""
    col = {name: log[name].to_numpy(float) for name in ("x", "y", "yaw", "lead_x", "lead_y", "lead_yaw")}
    return clear_gap_of_poses(col["x"], col["y"], col["yaw"], col["lead_x"], col["lead_y"], col["lead_yaw"],
                              _bumper_x_m())


def score_following(log: pd.DataFrame) -> FollowingOutcome:
    """The following outcome of one episode's log."""
    touched = log["collision_with"].astype(str).to_numpy() if "collision_with" in log else np.array([""] * len(log))
    hits = np.flatnonzero(touched == "lead")
    end = int(hits[0]) if hits.size else len(log)
    if "lead_x" not in log or not np.isfinite(log["lead_x"].to_numpy(float)).any():
        return FollowingOutcome(False, math.nan, math.nan, 0.0, 0, needless_hard_brakes(log))
    gap = gaps(log)[:max(end, 1)]
    ego = log["speed"].to_numpy(float)[:max(end, 1)]
    lead = log["lead_speed"].to_numpy(float)[:max(end, 1)]
    closing = ego - lead
    with np.errstate(divide="ignore", invalid="ignore"):
        ttc = np.where(closing > 1e-3, np.maximum(gap, 0.0) / closing, np.inf)
        headway = np.where(ego > MOVING_MPS, np.maximum(gap, 0.0) / ego, np.inf)
    min_ttc = 0.0 if hits.size else (float(ttc.min()) if np.isfinite(ttc).any() else math.nan)
    t = log["t"].to_numpy(float)[:max(end, 1)]
    dt = np.diff(t, prepend=t[0])
    moving = np.isfinite(headway) & np.isfinite(gap)
    mean_gap = float(headway[moving].mean()) if moving.any() else math.nan
    return FollowingOutcome(bool(hits.size), float(np.nanmin(gap)), min_ttc,
                            float(dt[headway < MIN_HEADWAY_S].sum()), hard_brakes(log), needless_hard_brakes(log),
                            mean_gap, float(log["t"].iloc[-1]))


def _hard(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(n - lag,) whether the speed ``v`` falls faster than ``HARD_BRAKE_MPS2`` over the 0.1 s after each step."""
    # Over 0.1 s, not a step: the wheels' contact makes the per-step speed jitter.
    lag = max(1, int(round(0.1 / max(float(np.median(np.diff(t))), 1e-3))))
    with np.errstate(invalid="ignore"):
        return (v[:-lag] - v[lag:]) / (t[lag:] - t[:-lag]) > HARD_BRAKE_MPS2


def _brake_starts(log: pd.DataFrame) -> np.ndarray:
    """The steps where a run of decelerations past ``HARD_BRAKE_MPS2`` begins."""
    t, v = log["t"].to_numpy(float), log["speed"].to_numpy(float)
    if len(t) < 3:
        return np.empty(0, int)
    hard = _hard(t, v)
    return np.flatnonzero(hard & ~np.concatenate([[False], hard[:-1]]))


def _lead_braked_before(log: pd.DataFrame, starts: np.ndarray) -> np.ndarray:
    """Whether the lead itself braked hard within ``ANSWER_S`` before (or at) each of ``starts``."""
    t, lead = log["t"].to_numpy(float), log["lead_speed"].to_numpy(float)
    hard = np.concatenate([_hard(t, lead), np.zeros(len(t) - len(_hard(t, lead)), bool)]) if len(t) >= 3 \
        else np.zeros(len(t), bool)
    when = t[hard]
    return np.array([bool(np.any((when <= t[k]) & (when >= t[k] - ANSWER_S))) for k in starts], bool)


def hard_brakes(log: pd.DataFrame) -> int:
    """How many times the ego car's deceleration went past ``HARD_BRAKE_MPS2`` (each run of steps once)."""
    return int(len(_brake_starts(log)))


def needless_hard_brakes(log: pd.DataFrame) -> int:
    """How many hard brakes began while the real lead asked for none: no lead at all, or its
    time-to-collision over ``NEEDLESS_TTC_S`` (or not closing), the headway at least ``MIN_HEADWAY_S``
    and no hard brake of the lead's within ``ANSWER_S`` before."""
    starts = _brake_starts(log)
    if not len(starts):
        return 0
    if "lead_x" not in log or not np.isfinite(log["lead_x"].to_numpy(float)).any():
        return int(len(starts))
    gap = np.maximum(gaps(log)[starts], 0.0)
    ego = log["speed"].to_numpy(float)[starts]
    closing = ego - log["lead_speed"].to_numpy(float)[starts]
    with np.errstate(divide="ignore", invalid="ignore"):
        ttc = np.where(closing > 1e-3, gap / closing, np.inf)
        headway = np.where(ego > MOVING_MPS, gap / ego, np.inf)
    answered = _lead_braked_before(log, starts)
    return int(np.count_nonzero((ttc > NEEDLESS_TTC_S) & (headway >= MIN_HEADWAY_S) & ~answered))
