"""Forecast-only baselines: Chronos-2 (the shipped prior, frozen) and four neuralforecast models.

Every forecaster maps context windows (the last W depths before a step) to the next H
steps. The benchmark builds the windows itself (:func:`context_windows`), one per scored
step and from data before that step only, so every forecaster is causal by construction
and all of them see identical windows.

The neuralforecast models (SOFTS, NHITS, DLinear, NLinear) are trained with the library's
own ``NeuralForecast.fit`` on the clean train series (W = 64, H = 16, MAE, fixed seed, CPU)
and forecast by calling the trained module on batches of windows, as the library's
predict step does (``model(windows)`` then ``loss.domain_map``; the models run with the
identity scaler, so there is nothing to invert). Tests check these forecasts against
``NeuralForecast.predict``. Trained weights are cached by a hash of everything that made
them (data, split, model settings, seed, library version), so a rerun only rescores.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from racf.experiments.offline.metrics import hold_last
from racf.provenance import atomic_write, code_version

__all__ = ["NF_MODELS", "NFSettings", "context_windows", "train_nf", "NFForecaster", "ChronosForecaster",
           "training_frame"]

#: The neuralforecast baselines, by the name the benchmark reports.
NF_MODELS = ("softs", "nhits", "dlinear", "nlinear")


@dataclass(frozen=True)
class NFSettings:
    """How the neuralforecast baselines are built and trained.

    Attributes:
        input_size: context W, steps.
        horizon: H, steps.
        max_steps: optimiser steps.
        batch_size: series per batch (univariate models).
        windows_batch_size: windows per step.
        learning_rate: Adam's.
        seed: the models' ``random_seed``.
        nhits_mlp_units: width of NHITS's MLPs (the library's default is 512; 256 trains in
            budget on 2 CPU cores).
        softs_hidden: SOFTS's hidden size and d_core (library default 512).
    """

    input_size: int = 64
    horizon: int = 16
    max_steps: int = 600
    batch_size: int = 32
    windows_batch_size: int = 256
    learning_rate: float = 1e-3
    seed: int = 0
    nhits_mlp_units: int = 256
    softs_hidden: int = 128

    def __post_init__(self) -> None:
        for name in ("input_size", "horizon", "max_steps", "batch_size", "windows_batch_size", "nhits_mlp_units",
                     "softs_hidden"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be > 0, got {self.learning_rate}")


def context_windows(values: np.ndarray, first: np.ndarray, origins: np.ndarray, width: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The ``width`` steps before each origin, within its series: (windows, mask), each (len(origins), width).

    Gaps (NaN) carry the last valid value forward, as a causal consumer would; ``mask`` is 1
    where the step had a real measurement. A window that reaches back past its series'
    start, or over steps with no value yet, is padded on the left with its own earliest
    value (mask 0); a window with no value at all is all NaN.
    """
    values = np.asarray(values, float)
    first = np.asarray(first, bool)
    held = hold_last(values, first)
    measured = np.isfinite(values).astype(float)
    series_start = np.maximum.accumulate(np.where(first, np.arange(len(values)), 0))
    windows = np.full((len(origins), width), np.nan)
    mask = np.zeros((len(origins), width))
    for row, t in enumerate(np.asarray(origins, int)):
        lo = max(series_start[t], t - width)
        part, part_mask = held[lo:t], measured[lo:t]
        ok = np.isfinite(part)
        part, part_mask = part[ok], part_mask[ok]
        if part.size:
            windows[row, width - part.size:] = part
            windows[row, :width - part.size] = part[0]
            mask[row, width - part.size:] = part_mask
    return windows, mask


def training_frame(frame: pd.DataFrame) -> pd.DataFrame:
    """A clean split as neuralforecast wants it: ``unique_id, ds, y, available_mask``.

    ``y`` is d_clean held over its gaps (no target in view); ``available_mask`` is 0 there,
    so the loss counts real measurements only. Steps before a series' first measurement are dropped.
    """
    parts = []
    for sid, s in frame.groupby("series_id", sort=False):
        y = s["d_clean"].to_numpy(float)
        ok = np.isfinite(y)
        if not ok.any():
            continue
        start = int(np.argmax(ok))
        y, ok = pd.Series(y[start:]).ffill().to_numpy(), ok[start:]
        parts.append(pd.DataFrame({"unique_id": str(sid), "ds": np.arange(len(y)), "y": y,
                                   "available_mask": ok.astype(float)}))
    if not parts:
        raise ValueError("the training split has no series with a measured distance")
    return pd.concat(parts, ignore_index=True)


def _quiet_lightning() -> None:
    """Lightning's banners and per-fit warnings off (it sets its loggers' levels on import, so after it)."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    import neuralforecast  # noqa: F401  (imports Lightning)

    for name in ("pytorch_lightning", "lightning", "lightning.pytorch", "lightning_fabric"):
        logging.getLogger(name).setLevel(logging.ERROR)
    import warnings

    for module in ("pytorch_lightning", "lightning", "neuralforecast"):
        warnings.filterwarnings("ignore", module=module)


def _build(name: str, s: NFSettings):
    from neuralforecast.models import DLinear, NHITS, NLinear, SOFTS

    common = dict(h=s.horizon, input_size=s.input_size, max_steps=s.max_steps, learning_rate=s.learning_rate,
                  random_seed=s.seed, scaler_type="identity", batch_size=s.batch_size, val_check_steps=s.max_steps,
                  enable_progress_bar=False, enable_model_summary=False, logger=False, enable_checkpointing=False,
                  accelerator="cpu", devices=1)
    if name == "dlinear":
        return DLinear(windows_batch_size=s.windows_batch_size, **common)
    if name == "nlinear":
        return NLinear(windows_batch_size=s.windows_batch_size, **common)
    if name == "nhits":
        return NHITS(windows_batch_size=s.windows_batch_size, mlp_units=3 * [[s.nhits_mlp_units] * 2], **common)
    if name == "softs":
        # SOFTS is multivariate: its STAR module pools across the series of a window. The
        # drives are independent, so it models one series at a time (n_series=1).
        return SOFTS(n_series=1, hidden_size=s.softs_hidden, d_core=s.softs_hidden, d_ff=2 * s.softs_hidden,
                     windows_batch_size=s.windows_batch_size, **common)
    raise ValueError(f"model must be one of {NF_MODELS}, got {name!r}")


def _cache_key(name: str, settings: NFSettings, train: pd.DataFrame) -> str:
    import neuralforecast
    import torch

    digest = hashlib.sha256()
    digest.update(json.dumps({"model": name, "settings": asdict(settings), "nf": neuralforecast.__version__,
                              "torch": torch.__version__, "code": code_version("racf.experiments.offline.forecasters")}, sort_keys=True).encode())
    digest.update(pd.util.hash_pandas_object(train, index=False).to_numpy().tobytes())
    return digest.hexdigest()[:16]


def train_nf(name: str, train: pd.DataFrame, settings: NFSettings, cache_dir: Path | None = None) -> "NFForecaster":
    """Trains (or loads from ``cache_dir``) one neuralforecast baseline on a ``training_frame``."""
    import torch

    _quiet_lightning()
    model = _build(name, settings)
    key = _cache_key(name, settings, train)
    cached = Path(cache_dir) / f"{name}-{key}.pt" if cache_dir is not None else None
    if cached is not None and cached.exists():
        model.load_state_dict(torch.load(cached, weights_only=True))
        return NFForecaster(name, model.eval(), settings, key, train_s=None)
    from neuralforecast import NeuralForecast

    t0 = time.perf_counter()
    frame = train
    if name == "softs":
        # One series for the n_series=1 model: the drives end to end (the few windows
        # across a seam are the price of the library's multivariate batching).
        frame = train.assign(unique_id="all", ds=np.arange(len(train)))
    nf = NeuralForecast(models=[model], freq=1)
    nf.fit(frame)
    model = nf.models[0]  # NeuralForecast trains its own copy of the model it is given
    train_s = time.perf_counter() - t0
    if cached is not None:
        cached.parent.mkdir(parents=True, exist_ok=True)
        state = model.state_dict()
        atomic_write(cached, lambda path: torch.save(state, path))
    return NFForecaster(name, model.eval(), settings, key, train_s=train_s)


@dataclass
class NFForecaster:
    """A trained neuralforecast model, forecasting batches of windows."""

    name: str
    model: object
    settings: NFSettings
    key: str
    train_s: float | None = None
    batch: int = field(default=4096)

    @property
    def n_parameters(self) -> int:
        return int(sum(p.numel() for p in self.model.parameters()))

    def forecast(self, windows: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """(B, W) windows (and their measured-mask) -> (B, H) forecasts; NaN rows stay NaN."""
        import torch

        windows = np.asarray(windows, float)
        mask = np.ones_like(windows) if mask is None else np.asarray(mask, float)
        out = np.full((len(windows), self.settings.horizon), np.nan)
        ok = np.isfinite(windows).all(axis=1)
        x = torch.tensor(windows[ok], dtype=torch.float32)
        m = torch.tensor(mask[ok], dtype=torch.float32)
        preds = []
        self.model.eval()  # dropout off, SOFTS's pooling deterministic
        with torch.no_grad():
            for start in range(0, len(x), self.batch):
                y = x[start:start + self.batch, :, None]  # [B, W, 1]: one series per window
                batch = {"insample_y": y, "insample_mask": m[start:start + self.batch, :, None], "futr_exog": None,
                         "hist_exog": None, "stat_exog": None}
                pred = self.model.loss.domain_map(self.model(batch))
                preds.append(pred.reshape(len(y), self.settings.horizon, -1)[..., 0].numpy())
        if preds:
            out[ok] = np.concatenate(preds)
        return out


class ChronosForecaster:
    """Chronos-2 forecast-only with the shipped prior (frozen, zero-shot on these series)."""

    name = "chronos"
    key = "shipped"
    train_s = None

    def __init__(self, horizon: int = 16, batch_size: int = 256) -> None:
        from racf.odca.prior import Chronos2Prior

        self.prior = Chronos2Prior(batch_size=batch_size)
        self.horizon = horizon

    @property
    def n_parameters(self) -> int:
        return int(sum(p.numel() for p in self.prior.model.parameters()))

    def forecast(self, windows: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """(B, W) windows -> (B, H) median forecasts (the mask is implied: Chronos sees the held values)."""
        return self.prior.forecast(np.asarray(windows, float), self.horizon)[0]
