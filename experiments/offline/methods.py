"""The repair methods of the offline benchmark, behind one shape: per-step estimates of a split.

Every method is causal (the estimate at step t uses data up to t) and returns one estimate
per step of a long-format corrupted frame:

- ``raw``: d~ held over its gaps (the last valid value of the series);
- ``lidar``: the aligned LiDAR reference alpha * l + beta where it reports;
- ``ekf``: :class:`racf.controllers.ekf.DistanceEKF` (depth with noise scaled by 1/c~, aligned
  LiDAR, odometry as control input);
- forecasters (``chronos``, ``softs``, ``nhits``, ``dlinear``, ``nlinear``): full replacement,
  the one-step-ahead forecast from the W depths before the step (:mod:`.forecasters`);
  computed at the scored steps only, with the next-H forecast kept for the horizon score;
- ``odca``: the online module's fused output (its batched path, identical to ``step``).

Every method starts afresh at each target (a new ``slot`` of a drive), as the car resets
its estimator when its track changes target. A method with no estimate at a step (no LiDAR
report, a filter not yet started, a forecaster with an empty context, ODCA with no target)
falls back to the held raw depth there, so every method is scored on the same steps: those
after the target's first valid depth measurement where d_clean exists.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from racf.controllers.ekf import DistanceEKF, EKFConfig
from racf.odca.align import Alignment
from racf.experiments.offline.metrics import hold_last
from racf.odca.features import sanitize

__all__ = ["METHODS", "FORECASTERS", "SplitArrays", "split_arrays", "raw_estimate", "lidar_estimate", "ekf_estimate",
           "forecast_at", "with_fallback"]

#: Every method, in table order.
METHODS = ("raw", "lidar", "ekf", "chronos", "softs", "nhits", "dlinear", "nlinear", "odca")
#: The forecast-only methods (scored one step ahead and over the horizon).
FORECASTERS = ("chronos", "softs", "nhits", "dlinear", "nlinear")


@dataclass(frozen=True)
class SplitArrays:
    """One corrupted split as aligned per-step arrays (series after series, in time order)."""

    series_id: np.ndarray
    first: np.ndarray  # True at each target's first step (a series' first, or a new slot)
    d: np.ndarray  # corrupted depth, NaN = missing
    c: np.ndarray
    l_al: np.ndarray  # aligned LiDAR reference, NaN = none
    v: np.ndarray
    label: np.ndarray  # 1 inside a corruption segment
    d_clean: np.ndarray
    d_true: np.ndarray
    raw: np.ndarray  # d held over its gaps, within the target
    kind: np.ndarray  # corruption segment kind (index into SEGMENT_KINDS; 0 = none)

    def __len__(self) -> int:
        return len(self.d)

    @property
    def scored(self) -> np.ndarray:
        """The steps every method is scored on: the target has been measured (a held raw value
        exists) and so does the reference. Before a target's first measurement no causal
        method can know it is there, and the held value would be another target's."""
        return np.isfinite(self.raw) & np.isfinite(self.d_clean)


def split_arrays(frame: pd.DataFrame, alignment: Alignment) -> SplitArrays:
    """Arrays of a corrupted frame (``dataset.corrupted(...)``: d_meas, c_meas, lidar, speed, label, ...)."""
    sid = frame["series_id"].to_numpy()
    first = np.r_[True, sid[1:] != sid[:-1]] if len(sid) else np.zeros(0, bool)
    if "slot" in frame and len(sid):
        slot = frame["slot"].to_numpy()
        first[1:] |= slot[1:] != slot[:-1]
    d, c, l, v, _, _ = sanitize(frame["d_meas"].to_numpy(float), frame["c_meas"].to_numpy(float),
                          frame["lidar"].to_numpy(float), frame["speed"].to_numpy(float))
    d_true = frame["d_true"].to_numpy(float) if "d_true" in frame else np.full(len(frame), np.nan)
    label = frame["label"].to_numpy(int)
    kind = frame["kind"].to_numpy(int) if "kind" in frame else label
    return SplitArrays(sid, first, d, c, alignment(l), v, label, frame["d_clean"].to_numpy(float), d_true,
                       hold_last(d, first), kind)


def with_fallback(estimate: np.ndarray, a: SplitArrays) -> np.ndarray:
    """The estimate where it exists, else the held raw depth."""
    return np.where(np.isfinite(estimate), estimate, a.raw)


def raw_estimate(a: SplitArrays) -> np.ndarray:
    return a.raw.copy()


def lidar_estimate(a: SplitArrays) -> np.ndarray:
    # Not held over its gaps: a silent LiDAR often means a new target not yet tracked, and
    # the last value would belong to the previous one.
    return with_fallback(a.l_al, a)


def ekf_estimate(a: SplitArrays, config: EKFConfig | None = None, dt: float = 0.02) -> np.ndarray:
    out = np.full(len(a), np.nan)
    ekf = DistanceEKF(config)
    for t in range(len(a)):
        if a.first[t]:
            ekf.reset()
        out[t] = ekf.step(a.d[t], a.c[t], a.l_al[t], a.v[t], dt)
    return with_fallback(out, a)


def forecast_at(forecaster, a: SplitArrays, origins: np.ndarray, width: int, horizon: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """One-step-ahead estimates at ``origins`` and the (len(origins), horizon) forecasts behind them.

    The context is the ``width`` corrupted depths before each origin (step t's own
    measurement is not used: a forecast of t from the past). With no context yet the
    one-step estimate falls back to the held raw depth.
    """
    from racf.experiments.offline.forecasters import context_windows

    windows, mask = context_windows(a.d, a.first, origins, width)
    paths = np.asarray(forecaster.forecast(windows, mask), float)[:, :horizon]
    one_step = np.where(np.isfinite(paths[:, 0]), paths[:, 0], a.raw[origins])
    return one_step, paths
