"""The distance estimators (defences) an episode runs, found by name in ``ESTIMATORS``
(:data:`racf.plugins.ESTIMATORS`, filled from the ``racf.estimators`` entry points).

Each is causal and sees, per 50 Hz step, the live depth distance, its confidence and
bearing, the LiDAR reference and the car's odometry (the ``DistanceEstimator`` protocol):

- ``raw``: d~ as perception measured it (no defence; NaN without a detection);
- ``odca``: the shipped ODCA checkpoint (frozen Chronos-2 prior, kinematic branch on the
  car's speed and yaw rate, the gate that votes, delta head);
- ``ekf``: the constant-velocity Kalman filter of depth and LiDAR with odometry;
- ``chronos``: Chronos-2 forecast-only: the prior's one-step-ahead mean from the last 64
  depth distances, refreshed every 4 steps as ODCA's is (full replacement of d~).

Each reports in ``diagnostics()["flag"]`` whether its detector flagged the step (ODCA: the
gate repaired it; the EKF: its innovation test; Chronos-only: the depth lies more than
3 standard deviations of the forecast from its mean; raw depth has no detector), and
answers ``would_pass(depth=..., ...)``: would a next step with this depth stay unflagged
(the question a white-box attacker asks; it changes nothing).

The ODCA checkpoint and the prior load once per process and are shared by the estimators a
worker or a service builds (loading takes about a second); each estimator keeps its own state.
"""

from __future__ import annotations

import inspect
import math
from functools import lru_cache
from typing import Any

import numpy as np

from racf.odca.features import usable_forecast
from racf.odca.gate import DEPTH, DEPTH_UNCONFIRMED

from racf.controllers import DistanceEstimator, PerceptionSample
from racf.plugins import ESTIMATORS

__all__ = ["ESTIMATORS", "make_estimator", "estimator_options", "check_options", "ODCAEstimator", "ChronosEstimator"]


def _odca(checkpoint: str | None, runtime: str = "torch"):
    """The loaded ODCA of ``checkpoint``, shared by the process's estimators: cached by the folder it
    resolves to (one folder spelt 20 ways is one load, not 20) and at most a few at once."""
    from pathlib import Path

    return _odca_loaded(None if checkpoint is None else str(Path(checkpoint).resolve()), runtime)


@lru_cache(maxsize=4)
def _odca_loaded(folder: str | None, runtime: str):
    from racf.odca import ODCA

    return ODCA.load(folder, runtime=runtime)


class ODCAEstimator:
    """ODCA's d_fused: depth passed through while it agrees with the LiDAR or the kinematic
    branch, repaired from the witnesses that agree when it is outvoted; NaN with no target.

    ``last`` holds the step's full output; ``diagnostics()`` logs the gate's verdict, its
    source and the kinematic branch.

    Args:
        checkpoint: the ODCA folder (None: the shipped one; with ``runtime="onnx"``, the shipped export).
        runtime: ``"torch"`` (the prior in PyTorch, the head in numpy) or ``"onnx"`` (both from the
            files of ``racf odca export``, run by onnxruntime on one thread: ODCA as the car runs it).
    """

    name = "odca"

    def __init__(self, checkpoint: str | None = None, runtime: str = "torch") -> None:
        from racf.odca.online import RUNTIMES

        if runtime not in RUNTIMES:
            raise ValueError(f"runtime must be one of {RUNTIMES}, got {runtime!r}")
        from racf.odca import ODCA

        # The loaded parts (config, head, prior) are shared by the process's estimators; the state
        # of an approach is each one's own: a service serves several cars at once.
        shared = _odca(checkpoint, runtime)
        self.model = ODCA(shared.config, shared.head, shared.prior)
        self.last = None
        self._had_depth = False
        self._size = (math.nan, math.nan)

    @property
    def n_parameters(self) -> int:
        """Trainable parameters: the delta head's (the prior is frozen)."""
        return self.model.head.n_parameters

    @property
    def n_frozen_parameters(self) -> int:
        return _prior_parameters(self.model.prior)

    @classmethod
    def of(cls, model) -> "ODCAEstimator":
        """The estimator around an ODCA model already in memory (the benchmark's per-split heads)."""
        estimator = cls.__new__(cls)
        estimator.model, estimator.last, estimator._had_depth = model, None, False
        estimator._size = (math.nan, math.nan)
        return estimator

    def reset(self) -> None:
        self.model.reset()
        self.last = None
        self._had_depth = False
        self._size = (math.nan, math.nan)

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self.last = self.model.step(depth=sample.d_meas, confidence=sample.c_meas, lidar=sample.lidar_m,
                                    speed=speed_mps, yaw_rate=yaw_rate_radps, bearing=sample.bearing_rad, dt=dt,
                                    lidar_confirmed=sample.lidar_confirmed, size=sample.d_size,
                                    size_std=sample.size_std)
        self._had_depth = math.isfinite(sample.d_meas)
        self._depth = sample.d_meas
        self._size = (sample.d_size, sample.size_std)
        return self.last.d_fused

    def follow_moving_target(self, speed_std_mps: float | None) -> None:
        """The gate's target moves, its speed this uncertain, m/s (``ODCA.follow_moving_target``)."""
        self.model.follow_moving_target(speed_std_mps)

    def use_calibration(self, calibration) -> None:
        """Sets the kinematic branch's lever (camera ahead of the rear axle) from the car's build;
        a checkpoint keeps the lever of the car it was trained for."""
        from dataclasses import replace

        from racf.odca import ODCA

        kinematics = self.model.config.kinematics
        if kinematics.camera_lever_m != calibration.camera_lever_m:
            config = replace(self.model.config, kinematics=replace(kinematics, camera_lever_m=calibration.camera_lever_m))
            self.model = ODCA(config, self.model.head, self.model.prior)

    def estimate_series(self, frame) -> np.ndarray:
        """d_fused over whole recorded series (``ODCA.run``, the batched path that gives the
        numbers ``estimate`` gives step by step): what the offline benchmark calls."""
        return self.model.run(frame)["d_fused"].to_numpy(float)

    def diagnostics(self) -> dict[str, float]:
        if self.last is None:
            return {}
        # The gate flags a depth it outvotes (or one off the kinematic baseline); a missing
        # depth, or one passed on first sight, is nothing to flag.
        flagged = self._had_depth and int(self.last.source) not in (DEPTH, DEPTH_UNCONFIRMED)
        return {"w": self.last.w, "flag": float(flagged), "score": self._score(), "odca_source": self.last.source,
                "d_kin": self.last.d_kin}

    def _score(self) -> float:
        """The depth's disagreement with its closest witness, in that witness's tolerance: the
        LiDAR's tau, the kinematic branch's tau + n_sigma x std (0: no depth, or no witness);
        or, if larger, how far the depth lies beyond the size witness, in its tolerance (the size
        vetoes on its own). The gate votes rather than thresholds this, so it is the statistic a
        threshold sweep reads."""
        last, cfg = self.last, self.model.config
        ratios = []
        if self._had_depth and math.isfinite(last.r_xs):
            ratios.append(last.r_xs / cfg.gate.tau_m)
        if self._had_depth and math.isfinite(last.d_kin) and math.isfinite(last.kin_std):
            ratios.append(abs(self._depth - last.d_kin) / (cfg.gate.tau_m + cfg.kinematics.n_sigma * last.kin_std))
        closest = min(ratios) if ratios else 0.0
        size, size_std = self._size
        if self._had_depth and math.isfinite(size) and math.isfinite(size_std):
            closest = max(closest, (self._depth - size) / cfg.gate.size_tolerance(size_std))
        return closest

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0, size_shift: float = 0.0) -> bool:
        return self.model.would_pass(depth=depth, speed=speed_mps, yaw_rate=yaw_rate_radps, lidar_shift=lidar_shift,
                                     dt=dt, size_shift=size_shift)


class ChronosEstimator:
    """Chronos-2 forecast-only: the prior's forecast for this step from the depths before it.

    Its detector flags a depth more than ``flag_sigma`` forecast standard deviations from the
    forecast's mean (a residual test; the estimate is the forecast either way).
    """

    name = "chronos"
    n_parameters = 0  # nothing trained for the task: the prior is used as it ships

    @property
    def n_frozen_parameters(self) -> int:
        return _prior_parameters(self.prior)

    def __init__(self, context_length: int = 64, horizon: int = 16, refresh_steps: int = 4,
                 flag_sigma: float = 3.0) -> None:
        self.prior = _odca(None).prior
        self.context_length, self.horizon, self.refresh_steps = context_length, horizon, refresh_steps
        self.flag_sigma = flag_sigma
        self.reset()

    def reset(self) -> None:
        self._context = np.full(self.context_length, np.nan)
        self._mean = np.full(self.horizon, np.nan)
        self._std = np.full(self.horizon, np.nan)
        self._t = 0
        self.flagged = False
        self._probe_cache: tuple = (-1, None, None)

    def _forecast(self) -> tuple[np.ndarray, np.ndarray]:
        if not np.isfinite(self._context).any():
            return np.full(self.horizon, np.nan), np.full(self.horizon, np.nan)
        mean, std = usable_forecast(*self.prior.forecast(self._context[None], self.horizon))
        return mean[0], std[0]

    def _residual_ok(self, d: float, mean: float, std: float) -> bool:
        return not (math.isfinite(d) and math.isfinite(mean) and math.isfinite(std)) or \
            abs(d - mean) <= self.flag_sigma * std

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        k = self._t % self.refresh_steps
        if k == 0:
            self._mean, self._std = self._forecast()
        d = sample.d_meas if math.isfinite(sample.d_meas) and sample.d_meas > 0 else math.nan
        self.flagged = not self._residual_ok(d, self._mean[k], self._std[k])
        self.score = (abs(d - self._mean[k]) / self._std[k] if math.isfinite(d) and math.isfinite(self._mean[k])
                      and math.isfinite(self._std[k]) and self._std[k] > 0 else 0.0)
        self._context = np.roll(self._context, -1)
        self._context[-1] = d
        self._t += 1
        return float(self._mean[k])

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        k = self._t % self.refresh_steps
        if k == 0:  # the next step refreshes the forecast: make it once per step however often asked
            if self._probe_cache[0] != self._t:
                self._probe_cache = (self._t, *self._forecast())
            _, mean, std = self._probe_cache
        else:
            mean, std = self._mean, self._std
        return self._residual_ok(depth, mean[k], std[k])

    def diagnostics(self) -> dict[str, float]:
        return {"flag": float(self.flagged), "score": self.score} if self._t else {}


def _prior_parameters(prior) -> int:
    model = getattr(prior, "model", None)
    if model is None:  # an exported prior counts its own (racf.odca.onnx_runtime)
        return int(getattr(prior, "n_parameters", 0))
    return int(sum(p.numel() for p in model.parameters()))


def make_estimator(name: str, options: dict[str, Any] | None = None) -> DistanceEstimator:
    """A fresh estimator by name (a key of ``ESTIMATORS``), built with ``options`` as keyword
    arguments (e.g. ``{"checkpoint": "outputs/odca-head"}``); ValueError names what is allowed."""
    cls = ESTIMATORS.plugin(name).obj
    options = dict(options or {})
    check_options(name, options)
    try:
        return cls(**options)
    except (TypeError, ValueError, OSError) as err:
        raise ValueError(f"estimator {name!r} with options {options}: {err}") from None


def estimator_options(name: str) -> tuple[str, ...]:
    """The keyword arguments estimator ``name`` takes (what ``--estimator-option`` may set)."""
    cls = ESTIMATORS.plugin(name).obj
    return tuple(k for k, p in inspect.signature(cls.__init__).parameters.items()
                 if k != "self" and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY))


def check_options(name: str, options: dict[str, Any]) -> None:
    """Fails before any episode on an option estimator ``name`` does not take."""
    if not isinstance(options, dict):
        raise ValueError(f"estimator options must be a table of name = value, got {options!r}")
    allowed = estimator_options(name)
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ValueError(f"estimator {name!r} has no option(s) {unknown}; it takes {list(allowed) or 'none'}")
    defaults = inspect.signature(ESTIMATORS.plugin(name).obj.__init__).parameters
    for key, value in options.items():
        kind = _kind(defaults[key].default)
        if kind is not None and not _is(kind, value):
            raise ValueError(f"estimator {name!r} option {key} must be {kind} (its default is "
                             f"{defaults[key].default!r}), got {value!r}")


def _kind(default: Any) -> str | None:
    """What an option's default says its values are: a number, true/false or text (None: anything)."""
    if isinstance(default, bool):
        return "true or false"
    if isinstance(default, (int, float)):
        return "a number"
    if isinstance(default, str):
        return "text"
    return None


def _is(kind: str, value: Any) -> bool:
    if kind == "true or false":
        return isinstance(value, bool)
    if kind == "a number":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    return isinstance(value, str)
