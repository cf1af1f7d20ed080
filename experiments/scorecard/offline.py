"""The scorecard's offline rows and cost: a defence run step by step, as the car runs it, on the
dataset's test drives under each corruption preset, beside Chronos-only on the same draws.

Rows: RMSE against the clean depth per preset (the mean over the draws, with the benchmark's
interval that resamples test drives and draws together) and the clean pass-through (the input
is the clean depth: the share of steps with a depth that come out unchanged, and the RMSE
against the input); the card adds the strong preset's RMSE as a ratio to Chronos-only's, scored
the same way on the same draws. The defence is scored as
it ships (ODCA with its shipped head, trained on the by-series train drives: the test drives
are unseen). Cost: the per-step time of ``estimate`` (median and p99, one thread) over the
strong preset's first draw, and the trainable parameters the defence declares
(``n_parameters``) or that its torch modules hold.
"""

from __future__ import annotations

import time

import numpy as np

from racf.experiments.offline.methods import estimator_estimate, split_arrays
from racf.experiments.offline.scoring import bootstrap_rmse_draws, mean_over_draws, recovery_scores, series_sse
from racf.controllers.perception import PerceptionSample

__all__ = ["offline_rows", "step_times_ms", "trainable_parameters"]

_BOOTSTRAP = 1000


def _make(name: str, options: dict | None = None):
    from racf.experiments.car.estimators import make_estimator

    return make_estimator(name, options)


def _alignment():
    from racf.experiments.car.estimators import ODCAEstimator

    return ODCAEstimator().model.config.alignment


def offline_rows(defence: str, ds, presets: tuple[str, ...], draws: int, options: dict | None = None) -> dict:
    """The offline rows of ``defence`` on ``ds`` (a ``QCarDataset``): per preset its RMSE with
    interval and N, and the clean pass-through."""
    alignment = _alignment()
    series = list(ds.split["test"])
    rows: dict = {}
    for preset in presets:
        per, sse = [], []
        for draw in range(draws):
            frame = ds.corrupted(preset, "test", draw)
            a = split_arrays(frame, alignment)
            est = estimator_estimate(_make(defence, options), a, frame)
            per.append(recovery_scores(est, a))
            sse.append(series_sse(est, a, series))
        mean = mean_over_draws(per)
        errors, counts = (np.stack([pair[i] for pair in sse], axis=1) for i in (0, 1))
        rows[preset] = {"rmse": mean["rmse"], "rmse_ci": bootstrap_rmse_draws(errors, counts, _BOOTSTRAP, 0),
                        "mae": mean["mae"], "n": mean["n"], "n_draws": draws, "n_series": len(series)}
    rows["clean_pass_through"] = _pass_through(defence, ds, alignment, options)
    return rows


def _pass_through(defence: str, ds, alignment, options: dict | None) -> dict:
    frame = ds.clean("test")
    clean = frame.assign(d_meas=frame["d_clean"], c_meas=frame["c_clean"], label=0)
    a = split_arrays(clean, alignment)
    out = estimator_estimate(_make(defence, options), a, clean)
    d = clean["d_meas"].to_numpy(float)
    has_d = np.isfinite(d) & np.isfinite(out)
    change = np.abs(out - d)[has_d]
    return {"unchanged_share": float(np.mean(change <= 1e-9)) if change.size else None,
            "rmse_vs_input_m": float(np.sqrt(np.mean(change ** 2))) if change.size else None,
            "n_depth": int(has_d.sum())}


def step_times_ms(defence: str, ds, options: dict | None = None, max_steps: int = 20000) -> dict:
    """Per-step time of ``estimate`` (ms) over the strong preset's first draw of the test drives."""
    alignment = _alignment()
    a = split_arrays(ds.corrupted("strong", "test", 0), alignment)
    est = _make(defence, options)
    times = []
    for t in range(min(len(a), max_steps)):
        if a.first[t]:
            est.reset()
        sample = PerceptionSample(None, float(a.d[t]), float(a.c[t]), float(a.l[t]), float(a.bearing[t]))
        t0 = time.perf_counter_ns()
        est.estimate(sample, float(a.v[t]), 0.02, float(a.w[t]))
        times.append(time.perf_counter_ns() - t0)
    ms = np.asarray(times, float) / 1e6
    return {"median_ms": float(np.median(ms)), "p99_ms": float(np.quantile(ms, 0.99)), "n_steps": len(ms)}


def trainable_parameters(defence: str, options: dict | None = None) -> dict:
    """The defence's trainable and frozen parameters, and where the count comes from: what it
    declares (``n_parameters``, ``n_frozen_parameters``), else its torch modules' parameters."""
    est = _make(defence, options)
    declared = getattr(est, "n_parameters", None)
    if isinstance(declared, int):
        return {"trainable": declared, "frozen": int(getattr(est, "n_frozen_parameters", 0) or 0),
                "from": "declared"}
    import torch

    seen, trainable, frozen = set(), 0, 0
    stack = [est]
    while stack:  # the torch modules reachable from the estimator's attributes
        obj = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, torch.nn.Module):
            for p in obj.parameters():
                trainable, frozen = (trainable + p.numel(), frozen) if p.requires_grad else (trainable,
                                                                                           frozen + p.numel())
            continue
        if hasattr(obj, "__dict__") and not isinstance(obj, type):
            stack.extend(v for v in vars(obj).values() if hasattr(v, "__dict__"))
    return {"trainable": trainable, "frozen": frozen, "from": "torch modules" if trainable + frozen else "none found"}
