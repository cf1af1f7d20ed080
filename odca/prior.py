"""The temporal prior: context -> mean and std over the next H steps, batched.

``TemporalPrior`` is the protocol; ``Chronos2Prior`` wraps ``chronos.Chronos2Pipeline``
(frozen) and loads a checkpoint by local path or hub id (``amazon/chronos-2`` for users
who can reach the Hugging Face hub); ``LastValuePrior`` is the naive baseline and a stub
for tests. The std comes from the predicted quantiles (the 10-90 % spread of a normal).

Forecasts run in fixed-size batches (padded), so a window gets bit-identical numbers
whether it is forecast alone (online) or with others (offline): CPU kernels compute the
rows of a fixed-shape batch independently, but pick different paths for other shapes.
The default batch is one window: the online module forecasts one window per refresh, and
a padded batch of 8 cost it 2.0 ms against 1.1 ms (``racf bench odca-latency``); offline callers
that want throughput pass a larger ``batch_size``.
"""

from __future__ import annotations

from racf.errors import UserError

from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, Protocol, runtime_checkable

import numpy as np
from racf.assets import asset_path

__all__ = ["TemporalPrior", "LastValuePrior", "Chronos2Prior", "CheckpointError", "SHIPPED_PRIOR", "checkpoint_prior"]

#: The project's own small Chronos-2-architecture checkpoint (see its MODEL_CARD.md).
SHIPPED_PRIOR = asset_path("checkpoints", "chronos2-racf-tiny")
_Z90 = 1.2815515655446004  # standard normal 90 % quantile


class CheckpointError(UserError):
    """A checkpoint that is missing, incomplete or corrupt."""


@runtime_checkable
class TemporalPrior(Protocol):
    """Forecasts the next ``horizon`` steps of each context window."""

    context_length: int

    def forecast(self, context: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
        """Args: context (B, W) float, NaN = missing. Returns (mean, std), each (B, horizon)."""


class LastValuePrior:
    """The last finite value, held; std = the context's recent step spread (a naive baseline)."""

    def __init__(self, context_length: int = 64) -> None:
        self.context_length = context_length

    def forecast(self, context: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
        ctx = _check_context(context)
        mean = np.full((ctx.shape[0], horizon), np.nan)
        std = np.full((ctx.shape[0], horizon), np.nan)
        for i, row in enumerate(ctx):
            finite = row[np.isfinite(row)]
            if finite.size:
                mean[i] = finite[-1]
                spread = np.std(np.diff(finite[-16:])) if finite.size > 2 else 0.0
                std[i] = spread * np.sqrt(np.arange(1, horizon + 1))
        return mean, std


class Chronos2Prior:
    """A frozen Chronos-2 forecaster.

    Args:
        checkpoint: local folder with ``config.json`` + weights, or a hub id.
        batch_size: the fixed batch the model always runs with (see the module docstring).
    """

    def __init__(self, checkpoint: str | Path = SHIPPED_PRIOR, batch_size: int = 1) -> None:
        import torch
        from chronos import Chronos2Pipeline

        path = Path(checkpoint)
        looks_local = path.is_absolute() or str(checkpoint).startswith(".") or path.exists()
        if looks_local and not (path / "config.json").exists():
            raise CheckpointError(f"no Chronos-2 checkpoint at {path} (need config.json and model weights; "
                                  "`racf odca pretrain-prior` makes one)")
        try:
            with _quiet_transformers():
                pipeline = Chronos2Pipeline.from_pretrained(str(checkpoint))
        except Exception as err:  # transformers raises many kinds; the user needs one message
            raise CheckpointError(f"could not load the Chronos-2 checkpoint {checkpoint}: "
                                  f"{type(err).__name__}: {err}") from None
        self.pipeline = pipeline
        self.model = pipeline.model.eval()
        self.context_length = int(pipeline.model_context_length)
        self.quantiles = np.asarray(pipeline.quantiles, float)
        self.batch_size = int(batch_size)
        self._group_ids = torch.arange(self.batch_size)
        self._torch = torch
        lo, hi = np.argmin(np.abs(self.quantiles - 0.1)), np.argmin(np.abs(self.quantiles - 0.9))
        mid = np.argmin(np.abs(self.quantiles - 0.5))
        self._lo, self._hi, self._mid = int(lo), int(hi), int(mid)
        self._traced: dict = {}

    def _forward(self, batch, n_patches: int):
        """The model's quantile forecasts for one padded batch, through a TorchScript trace.

        The trace runs the same kernels as the eager model (tests check the outputs are
        bit-identical, NaN patterns included) without Python's per-module overhead: about
        half the time of an eager call, which is most of ODCA's cost on a refresh step.
        """
        torch = self._torch
        key = (tuple(batch.shape), n_patches)
        if key not in self._traced:
            import warnings

            with warnings.catch_warnings(), _quiet_transformers():
                warnings.simplefilter("ignore")  # tracer warnings about Python values
                self._traced[key] = torch.jit.trace(self.quantile_module(n_patches), (batch, self._group_ids),
                                                    check_trace=False)
        return self._traced[key](batch, self._group_ids)

    def quantile_module(self, n_patches: int):
        """The frozen model as a module of (context, group_ids) -> its quantile forecasts over
        ``n_patches`` output patches: what is traced here and exported for the car
        (:mod:`racf.odca.onnx_export`)."""
        torch, model = self._torch, self.model

        class QuantileForecast(torch.nn.Module):
            def __init__(self) -> None:
                super().__init__()
                self.model = model

            def forward(self, context, group_ids):
                return self.model(context, group_ids=group_ids, num_output_patches=n_patches).quantile_preds

        return QuantileForecast().eval()

    def forecast(self, context: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
        """Median and quantile-spread std for each window; NaN where a window has no finite value.

        Args:
            context: (B, W) windows, NaN = missing; only the last ``context_length`` are used.
            horizon: steps ahead (<= the checkpoint's prediction length).
        Returns:
            (mean, std), each (B, horizon).
        """
        torch = self._torch
        ctx = _check_context(context)[:, -self.context_length:].astype(np.float32)
        patch = int(self.pipeline.model_output_patch_size)
        n_patches = -(-horizon // patch)
        out_q = np.full((ctx.shape[0], len(self.quantiles), n_patches * patch), np.nan, np.float32)
        seen = np.isfinite(ctx).any(axis=1)
        with torch.no_grad():
            for start in range(0, ctx.shape[0], self.batch_size):
                if not seen[start:start + self.batch_size].any():
                    continue  # nothing to forecast from: the answer is NaN (below) without the model
                chunk = ctx[start:start + self.batch_size]
                # NaN marks missing values: the model masks them itself (zeros plus a mask leak through).
                padded = np.zeros((self.batch_size, ctx.shape[1]), np.float32)
                padded[:len(chunk)] = chunk
                pred = self._forward(torch.from_numpy(padded), n_patches)
                out_q[start:start + len(chunk)] = pred[:len(chunk)].numpy()
        q = out_q[..., :horizon].astype(float)
        mean = q[:, self._mid]
        std = np.maximum((q[:, self._hi] - q[:, self._lo]) / (2 * _Z90), 0.0)
        mean[~seen], std[~seen] = np.nan, np.nan
        return mean, std


def checkpoint_prior(name: str, folder: Path) -> Chronos2Prior:
    """The prior an ODCA checkpoint in ``folder`` names: ``"shipped"``, a path (absolute or relative
    to the folder) or a hub id."""
    if name == "shipped":
        return Chronos2Prior(SHIPPED_PRIOR)
    path = Path(name)
    if not path.is_absolute() and (folder / path).exists():
        path = folder / path
    return Chronos2Prior(path if path.exists() else name)


@contextmanager
def _quiet_transformers() -> Iterator[None]:
    """Loads without transformers' info and warnings (``loss_type=None ...``) or its "Loading
    weights" bar, which every worker of a sweep would print around the sweep's own bar; errors
    still show. The library's settings are restored after."""
    from transformers.utils import logging as hf_logging

    verbosity, bar = hf_logging.get_verbosity(), hf_logging.is_progress_bar_enabled()
    hf_logging.set_verbosity_error()
    hf_logging.disable_progress_bar()
    try:
        yield
    finally:
        hf_logging.set_verbosity(verbosity)
        if bar:
            hf_logging.enable_progress_bar()


def _check_context(context: np.ndarray) -> np.ndarray:
    ctx = np.asarray(context, float)
    if ctx.ndim != 2 or ctx.shape[1] < 1:
        raise ValueError(f"context must be a (batch, window) array, got shape {ctx.shape}")
    return np.where(np.isfinite(ctx), ctx, np.nan)
