"""Scoring: a pure function from an episode's per-step log to each target's outcome.

Definitions (``docs/protocol.md``):

- success: the car comes to rest (speed < 0.05 m/s) with its front bumper 0 to 0.60 m
  before the stop line;
- t*: the first step at which the reference controller (the same braking controller fed
  d_true while the target is in view; the log's ``ideal_brake``) commands the brake;
- trigger delay = t(first brake command) - t*;
- dt_brake (the paper's braking latency): from t* to the first step at which the
  controller under test is braking with the front bumper within 0.60 m of the line.

Failures are named by where they come from: ``never_confirmed`` (no confirmed track before
the line), ``confirmed_lost`` (a track was confirmed but lost, and no brake came after),
``braked_late`` (braked, but came to rest past the line or ran it), ``braked_early``
(came to rest more than 0.60 m before the line: phantom or early braking), ``timeout``.
Stealth (``stealth``): the **undetected error** is the largest |d_fused - d_true| over the
attacked steps before the defence's detector first flags one (``flag``: ODCA's gate, the
EKF's innovation test, Chronos-only's residual test; raw depth has none, so every attacked
step counts); the **detection delay** is the time from the attack's start to that first flag.

Old logs can be rescored: nothing here reads the simulator.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

__all__ = ["TargetOutcome", "score_target", "score_log", "largest_jump", "stealth", "Stealth", "SUCCESS_BAND_M",
           "AT_REST_MPS", "FAILURES"]

#: The protocol's success band: front bumper this far before the stop line, metres.
SUCCESS_BAND_M = (0.0, 0.60)
#: At rest below this speed, m/s.
AT_REST_MPS = 0.05
#: Failure causes, in the order tables show them.
FAILURES = ("never_confirmed", "confirmed_lost", "braked_late", "braked_early", "timeout")
#: Columns the scorer reads.
LOG_COLUMNS = ("t", "slot", "speed", "dist_to_stop_line", "brake", "ideal_brake", "confirmed")


@dataclass(frozen=True)
class TargetOutcome:
    """What one target of an episode came to."""

    slot: int
    success: bool
    failure: str | None
    rest_distance_m: float
    t_star_s: float
    t_brake_s: float
    trigger_delay_s: float
    dt_brake_s: float
    confirmed: bool

    def to_dict(self) -> dict:
        return asdict(self)


def score_target(steps: pd.DataFrame) -> TargetOutcome:
    """The outcome of one target from its steps of the log (``LOG_COLUMNS``, time-ordered)."""
    missing = [c for c in LOG_COLUMNS if c not in steps]
    if missing:
        raise ValueError(f"the log lacks column(s) {missing}; a scoreable log has {list(LOG_COLUMNS)}")
    if steps.empty:
        raise ValueError("no steps to score")
    t = steps["t"].to_numpy(float)
    speed = np.abs(steps["speed"].to_numpy(float))
    dist = steps["dist_to_stop_line"].to_numpy(float)
    brake = steps["brake"].to_numpy(bool)
    ideal = steps["ideal_brake"].to_numpy(bool)
    confirmed = steps["confirmed"].to_numpy(bool)

    at_rest = np.flatnonzero((speed < AT_REST_MPS) & (t > 0))
    rest = float(dist[at_rest[0]]) if at_rest.size else math.nan
    t_star = _first(t, ideal)
    t_brake = _first(t, brake)
    t_near = _first(t, brake & (dist <= SUCCESS_BAND_M[1]))
    success = SUCCESS_BAND_M[0] <= rest <= SUCCESS_BAND_M[1]
    failure = None
    if not success:
        if math.isnan(t_brake):
            failure = "confirmed_lost" if confirmed[dist >= 0].any() else "never_confirmed"
        elif rest > SUCCESS_BAND_M[1]:
            failure = "braked_early"
        elif rest < SUCCESS_BAND_M[0] or dist.min() < 0:
            failure = "braked_late"
        else:  # braking when the episode ended
            failure = "timeout"
    return TargetOutcome(int(steps["slot"].iloc[0]), bool(success), failure, rest, t_star, t_brake,
                         t_brake - t_star, t_near - t_star, bool(confirmed.any()))


def score_log(log: pd.DataFrame) -> list[TargetOutcome]:
    """One outcome per target slot of an episode's log, in the order the targets were met."""
    return [score_target(steps) for _, steps in log.groupby("slot", sort=True)]


def largest_jump(log: pd.DataFrame) -> float:
    """The largest change of the distance estimate between two controller steps of the same
    target beyond what the car's own motion explains: max |d(t) - d(t') + v(t) (t - t')|, m
    (the protocol's no-jump bound; NaN when no two consecutive controller steps both have a
    distance). Reads ``t``, ``slot``, ``control``, ``d_fused`` and the measured speed."""
    steps = log[log["control"].astype(bool)] if "control" in log else log
    d = steps["d_fused"].to_numpy(float)
    t = steps["t"].to_numpy(float)
    speed = steps["state_speed_mps" if "state_speed_mps" in steps else "speed"].to_numpy(float)
    slot = steps["slot"].to_numpy()
    same = (slot[1:] == slot[:-1]) & np.isfinite(d[1:]) & np.isfinite(d[:-1])
    excess = np.abs(d[1:] - d[:-1] + speed[1:] * (t[1:] - t[:-1]))[same]
    return float(excess.max()) if excess.size else math.nan


@dataclass(frozen=True)
class Stealth:
    """How far an attack pushed the distance the car acted on before the defence noticed.

    ``undetected_error_m``: max |d_fused - d_true| over the attacked steps before the first
    flag (NaN: no attacked step with both); ``detection_delay_s``: attack start to the first
    flag (NaN: never flagged, or no attack); ``detected``: whether a flag came.
    """

    undetected_error_m: float
    detection_delay_s: float
    detected: bool


def stealth(log: pd.DataFrame) -> Stealth:
    """The stealth measures of one episode's log (reads ``t``, ``attack_active``, ``d_fused``,
    ``d_true`` and ``flag``: NaN or missing where the defence has no detector)."""
    active = log["attack_active"].to_numpy(bool) if "attack_active" in log else np.zeros(len(log), bool)
    if not active.any():
        return Stealth(math.nan, math.nan, False)
    t = log["t"].to_numpy(float)
    flag = log["flag"].to_numpy(float) if "flag" in log else np.full(len(log), np.nan)
    start = int(np.argmax(active))
    flagged = np.flatnonzero((flag == 1.0) & (np.arange(len(log)) >= start))
    until = int(flagged[0]) if flagged.size else len(log)
    quiet = active.copy()
    quiet[until:] = False
    err = np.abs(log["d_fused"].to_numpy(float) - log["d_true"].to_numpy(float))[quiet]
    err = err[np.isfinite(err)]
    return Stealth(float(err.max()) if err.size else math.nan,
                   float(t[until] - t[start]) if flagged.size else math.nan, bool(flagged.size))


def _first(t: np.ndarray, mask: np.ndarray) -> float:
    idx = np.flatnonzero(mask)
    return float(t[idx[0]]) if idx.size else math.nan
