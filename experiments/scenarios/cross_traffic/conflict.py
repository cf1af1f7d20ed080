"""What a stop cost: the episode's conflict with cross-traffic, scored from the step log.

Pure, like :mod:`~racf.experiments.episode.scoring`: it reads the referee's columns (the ego
car's true pose and speed, each other car's, the conflict point, what the car touched) and
nothing else, so a stored log can be rescored.

- **collision**: the first contact the env reported (``collision_with``): another car
  (``traffic0``..) or anything else (a wall, a pole).
- **time-to-collision** (TTC): at each step, how long until the two cars' footprints
  (0.425 x 0.192 m boxes) would overlap if both kept their velocity; the episode's smallest,
  before any contact (0 at contact; NaN: never on a collision course within ``TTC_HORIZON_S``).
- **post-encroachment time** (PET): between the first car leaving the conflict zone (a disc of
  ``CONFLICT_ZONE_M`` around the conflict point) and the other entering it; 0 when both are in
  it at once; NaN when the ego car never entered it.
- **outcome**: ``collision`` (with another car), ``crash`` (with anything else), ``yielded``
  (the ego car never entered the conflict zone), ``near_miss`` (it entered it, and TTC or PET
  was under ``NEAR_MISS_S``), ``passed`` (it crossed the zone with room to spare); None
  without traffic.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from racf.sim.world.traffic import CAR_FOOTPRINT_M, MAX_TRAFFIC_CARS

__all__ = ["ConflictOutcome", "score_conflict", "CONFLICT_OUTCOMES", "CAR_FOOTPRINT_M", "CONFLICT_ZONE_M",
           "TTC_HORIZON_S", "NEAR_MISS_S"]

#: The conflict zone's radius around the conflict point, m: a footprint inside it blocks the other lane.
CONFLICT_ZONE_M = 0.15
#: How far ahead TTC looks, s.
TTC_HORIZON_S = 3.0
_TTC_STEP_S = 0.02
#: TTC or PET below this is a near miss, s (the surrogate-safety literature's usual 1-1.5 s).
NEAR_MISS_S = 1.0
#: Conflict outcomes, in the order tables show them.
CONFLICT_OUTCOMES = ("collision", "crash", "near_miss", "passed", "yielded")


@dataclass(frozen=True)
class ConflictOutcome:
    """One episode's conflict with cross-traffic (every field None/NaN/False without traffic)."""

    conflict: str | None
    collision: bool
    collision_with: str | None
    min_ttc_s: float
    pet_s: float

    def to_dict(self) -> dict:
        return asdict(self)


def score_conflict(log: pd.DataFrame) -> ConflictOutcome:
    """The conflict outcome of one episode's log."""
    touched = log["collision_with"].astype(str) if "collision_with" in log else pd.Series([""] * len(log))
    hits = np.flatnonzero(touched.to_numpy() != "")
    collision_with = str(touched.iloc[hits[0]]) if hits.size else None
    cars = [k for k in range(MAX_TRAFFIC_CARS)
            if f"traffic{k}_x" in log and np.isfinite(log[f"traffic{k}_x"].to_numpy(float)).any()]
    if not cars:
        return ConflictOutcome(None, collision_with is not None, collision_with, math.nan, math.nan)
    end = int(hits[0]) if hits.size else len(log)
    t = log["t"].to_numpy(float)
    ego = _states(log, "", end)
    others = [_states(log, f"traffic{k}_", end) for k in cars]
    ttc = 0.0 if hits.size and collision_with.startswith("traffic") else _min_ttc(ego, others)
    point = np.array([log["conflict_x"].iloc[0], log["conflict_y"].iloc[0]], float)
    pet = _pet(t, ego, others, point, len(log))
    if collision_with is not None:
        outcome = "collision" if collision_with.startswith("traffic") else "crash"
    elif math.isnan(pet):  # it stayed out of the conflict zone: a short TTC on the way was resolved by stopping
        outcome = "yielded"
    elif ttc < NEAR_MISS_S or pet < NEAR_MISS_S:
        outcome = "near_miss"
    else:
        outcome = "passed"
    return ConflictOutcome(outcome, collision_with is not None, collision_with, ttc, pet)


def _states(log: pd.DataFrame, prefix: str, end: int) -> np.ndarray:
    """(n, 4) x, y, yaw, speed of one car over the log's first ``end`` steps (up to the first contact)."""
    return log[[f"{prefix}{f}" for f in ("x", "y", "yaw", "speed")]].to_numpy(float)[:max(end, 1)]


def _corners(x: np.ndarray, y: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """(..., 4, 2) footprint corners."""
    half_l, half_w = CAR_FOOTPRINT_M[0] / 2, CAR_FOOTPRINT_M[1] / 2
    local = np.array([[half_l, half_w], [half_l, -half_w], [-half_l, -half_w], [-half_l, half_w]])
    c, s = np.cos(yaw)[..., None], np.sin(yaw)[..., None]
    return np.stack([x[..., None] + c * local[:, 0] - s * local[:, 1],
                     y[..., None] + s * local[:, 0] + c * local[:, 1]], axis=-1)


def _overlap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether two sets of rectangles (..., 4, 2) overlap (separating axes: the four edge normals)."""
    axes = np.concatenate([a[..., 1:3, :] - a[..., 0:2, :], b[..., 1:3, :] - b[..., 0:2, :]], axis=-2)
    pa = np.einsum("...kd,...jd->...jk", a, axes)
    pb = np.einsum("...kd,...jd->...jk", b, axes)
    separated = (pa.max(-1) < pb.min(-1)) | (pb.max(-1) < pa.min(-1))
    return ~separated.any(-1)


def _min_ttc(ego: np.ndarray, others: list[np.ndarray]) -> float:
    taus = np.arange(0.0, TTC_HORIZON_S + 1e-9, _TTC_STEP_S)
    best = math.inf
    for other in others:
        n = min(len(ego), len(other))
        pos = []
        for s in (ego[:n], other[:n]):
            x = s[:, 0, None] + s[:, 3, None] * np.cos(s[:, 2, None]) * taus
            y = s[:, 1, None] + s[:, 3, None] * np.sin(s[:, 2, None]) * taus
            pos.append(_corners(x, y, np.repeat(s[:, 2, None], len(taus), axis=1)))
        hit = _overlap(*pos) & np.isfinite(other[:n, :1])
        rows = hit.any(axis=1)
        if rows.any():
            best = min(best, float(taus[hit[rows].argmax(axis=1)].min()))
    return best if math.isfinite(best) else math.nan


def _pet(t: np.ndarray, ego: np.ndarray, others: list[np.ndarray], point: np.ndarray, n_steps: int) -> float:
    def occupancy(s: np.ndarray) -> np.ndarray:
        # Distance from the point to the footprint, in the car's frame.
        dx, dy = point[0] - s[:, 0], point[1] - s[:, 1]
        c, sn = np.cos(s[:, 2]), np.sin(s[:, 2])
        along, across = np.abs(c * dx + sn * dy), np.abs(-sn * dx + c * dy)
        gap = np.hypot(np.maximum(along - CAR_FOOTPRINT_M[0] / 2, 0), np.maximum(across - CAR_FOOTPRINT_M[1] / 2, 0))
        return gap < CONFLICT_ZONE_M

    ego_in = np.flatnonzero(occupancy(ego))
    if not ego_in.size:
        return math.nan
    ego_span = (t[ego_in[0]], t[ego_in[-1]])
    best = math.inf
    for other in others:
        inside = np.flatnonzero(occupancy(other) & np.isfinite(other[:, 0]))
        if not inside.size:
            continue
        span = (t[inside[0]], t[inside[-1]])
        first, second = (ego_span, span) if ego_span[0] <= span[0] else (span, ego_span)
        best = min(best, max(0.0, second[0] - first[1]))
    return best if math.isfinite(best) else math.inf
