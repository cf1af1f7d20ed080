"""The repair methods of the offline benchmark, behind one shape: per-step estimates of a split.

Every method is causal (the estimate at step t uses data up to t) and returns one estimate
per step of a long-format corrupted frame:

- every registered estimator (``racf.plugins.ESTIMATORS``: ``raw``, ``ekf``, ``odca`` and any
  plug-in), run step by step on the recorded series exactly as the car runs it
  (:func:`estimator_estimate`): the same class, the same ``estimate`` call. ``raw`` is d~, held
  over its gaps by the fallback below; ``odca`` is the split's retrained head (its batched
  path, ``estimate_series``, gives the numbers ``step`` gives);
- ``lidar``: the aligned LiDAR reference alpha * l + beta where it reports (a reference, not a
  defence a car runs);
- forecasters (``chronos``, ``softs``, ``nhits``, ``dlinear``, ``nlinear``): offline-only, full
  replacement, the one-step-ahead forecast from the W depths before the step
  (:mod:`.forecasters`); computed at the scored steps only, with the next-H forecast kept for
  the horizon score. The ``chronos`` estimator of the closed loop is scored here as this
  forecaster (the prior it wraps), which the horizon score needs.

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

from racf.controllers.perception import PerceptionSample
from racf.experiments.offline.metrics import hold_last
from racf.odca.align import Alignment
from racf.odca.features import sanitize
from racf.plugins import ESTIMATORS

__all__ = ["METHODS", "FORECASTERS", "SplitArrays", "split_arrays", "raw_estimate", "lidar_estimate",
           "estimator_estimate", "offline_estimators", "table_order", "forecast_at", "with_fallback", "STEP_S"]

#: racf's own methods, in table order (plug-in estimators follow, by name: :func:`table_order`).
METHODS = ("raw", "lidar", "ekf", "chi2", "cusum", "chronos", "softs", "nhits", "dlinear", "nlinear", "odca")
#: The forecast-only methods (scored one step ahead and over the horizon).
FORECASTERS = ("chronos", "softs", "nhits", "dlinear", "nlinear")
#: The dataset's step, s (50 Hz).
STEP_S = 0.02


def offline_estimators() -> tuple[str, ...]:
    """The registered estimators the benchmark runs step by step: all but those a forecaster of
    the same name scores (``chronos``), and those that answer whether a sign stands
    (``existence``: they read the live frame's witnesses, which a recorded series does not hold)."""
    return tuple(name for name in ESTIMATORS
                 if name not in FORECASTERS and not getattr(ESTIMATORS[name], "existence", False))


def table_order(names) -> list[str]:
    """``names`` in table order: racf's methods first, then the others (plug-ins) by name."""
    names = set(names)
    return [m for m in METHODS if m in names] + sorted(names - set(METHODS))


@dataclass(frozen=True)
class SplitArrays:
    """One corrupted split as aligned per-step arrays (series after series, in time order)."""

    series_id: np.ndarray
    first: np.ndarray  # True at each target's first step (a series' first, or a new slot)
    d: np.ndarray  # corrupted depth, NaN = missing
    c: np.ndarray
    l_al: np.ndarray  # aligned LiDAR reference, NaN = none
    l: np.ndarray  # the LiDAR reference as the car's tracker reports it, NaN = none
    v: np.ndarray
    w: np.ndarray  # yaw rate, rad/s
    bearing: np.ndarray  # the detection's bearing, rad (NaN: none)
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
    d, c, l, v, w, b = sanitize(frame["d_meas"].to_numpy(float), frame["c_meas"].to_numpy(float),
                                frame["lidar"].to_numpy(float), frame["speed"].to_numpy(float),
                                frame["yaw_rate"].to_numpy(float) if "yaw_rate" in frame else 0.0,
                                frame["bearing"].to_numpy(float) if "bearing" in frame else np.nan)
    w, b = np.broadcast_to(w, d.shape), np.broadcast_to(b, d.shape)
    d_true = frame["d_true"].to_numpy(float) if "d_true" in frame else np.full(len(frame), np.nan)
    label = frame["label"].to_numpy(int)
    kind = frame["kind"].to_numpy(int) if "kind" in frame else label
    return SplitArrays(sid, first, d, c, alignment(l), l, v, w, b, label, frame["d_clean"].to_numpy(float), d_true,
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


def estimator_estimate(estimator, a: SplitArrays, frame: pd.DataFrame | None = None, dt: float = STEP_S) -> np.ndarray:
    """A ``DistanceEstimator``'s estimates over a split, step by step as the car runs it: reset at
    each target, then ``estimate(sample, speed, dt, yaw_rate)`` with the step's depth, confidence,
    LiDAR reference and bearing. An estimator with a batched path (``estimate_series(frame)``,
    which must give the numbers ``estimate`` gives) is run through it on ``frame``."""
    batched = getattr(estimator, "estimate_series", None)
    if callable(batched) and frame is not None:
        return with_fallback(np.asarray(batched(frame), float), a)
    out = np.full(len(a), np.nan)
    for t in range(len(a)):
        if a.first[t]:
            estimator.reset()
        sample = PerceptionSample(None, float(a.d[t]), float(a.c[t]), float(a.l[t]), float(a.bearing[t]))
        out[t] = estimator.estimate(sample, float(a.v[t]), dt, float(a.w[t]))
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
