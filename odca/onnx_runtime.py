"""ODCA onboard: the exported prior and head (``racf odca export``) run by onnxruntime, one thread,
with no PyTorch in the process. ``ODCA.load(folder, runtime="onnx")`` builds ODCA from them; the
gate and the kinematic branch are the same numpy code as on the PyTorch path."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from racf.odca.head import HeadWeights
from racf.odca.prior import CheckpointError, _check_context

__all__ = ["OnnxPrior", "OnnxHead", "read_export", "SHIPPED_ONNX", "EXPORT_FILE", "PRIOR_FILE", "HEAD_FILE"]

#: The files of an export (``racf odca export``, :mod:`racf.odca.onnx_export`).
EXPORT_FILE, PRIOR_FILE, HEAD_FILE = "export.json", "prior.onnx", "head.onnx"

_Z90 = 1.2815515655446004


def _shipped() -> Path:
    from racf.assets import asset_path

    return asset_path("checkpoints", "odca-onnx")


SHIPPED_ONNX = _shipped()


def read_export(folder: str | Path) -> dict:
    """The manifest of an exported folder; CheckpointError names what is missing."""
    folder = Path(folder)
    missing = [f for f in (EXPORT_FILE, PRIOR_FILE, HEAD_FILE, "odca.json", "head.npz") if not (folder / f).is_file()]
    if missing:
        raise CheckpointError(f"no exported ODCA at {folder} (missing {', '.join(missing)}; `racf odca export "
                              f"{folder}` makes one)")
    try:
        return json.loads((folder / EXPORT_FILE).read_text())
    except json.JSONDecodeError as err:
        raise CheckpointError(f"{folder / EXPORT_FILE} is not JSON ({err}); export the checkpoint again") from None


def _session(path: Path):
    import onnxruntime as ort

    options = ort.SessionOptions()
    # One thread, as on the car beside its other work; no spinning threads between calls.
    options.intra_op_num_threads = options.inter_op_num_threads = 1
    options.log_severity_level = 3
    try:
        return ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    except Exception as err:  # onnxruntime raises its own kinds for a file it cannot load
        raise CheckpointError(f"onnxruntime cannot load {path}: {type(err).__name__}: {err}") from None


class OnnxPrior:
    """The exported Chronos-2 prior: the ``TemporalPrior`` protocol (median and quantile-spread
    std), one window per call as the online module asks."""

    def __init__(self, folder: str | Path, manifest: dict | None = None) -> None:
        folder = Path(folder)
        meta = (manifest or read_export(folder))["prior"]
        self.context_length = int(meta["context_length"])
        self.n_parameters = int(meta["n_parameters"])
        self.quantiles = np.asarray(meta["quantiles"], float)
        self.horizon_max = int(meta["output_patches"]) * int(meta["patch"])
        self._session = _session(folder / meta["file"])
        self._group = np.zeros(1, np.int64)
        self._lo, self._hi = (int(np.argmin(np.abs(self.quantiles - q))) for q in (0.1, 0.9))
        self._mid = int(np.argmin(np.abs(self.quantiles - 0.5)))

    def forecast(self, context: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
        if horizon > self.horizon_max:
            raise ValueError(f"the exported prior forecasts {self.horizon_max} steps; asked for {horizon}")
        ctx = _check_context(context)[:, -self.context_length:].astype(np.float32)
        mean = np.full((ctx.shape[0], horizon), np.nan)
        std = np.full((ctx.shape[0], horizon), np.nan)
        for i, row in enumerate(ctx):
            if not np.isfinite(row).any():
                continue  # nothing to forecast from: NaN, as the PyTorch prior answers
            window = np.zeros((1, self.context_length), np.float32)
            window[0, self.context_length - row.size:] = row
            if row.size < self.context_length:
                window[0, :self.context_length - row.size] = np.nan
            q = self._session.run(None, {"context": window, "group_ids": self._group})[0][0, :, :horizon].astype(float)
            mean[i] = q[self._mid]
            std[i] = np.maximum((q[self._hi] - q[self._lo]) / (2 * _Z90), 0.0)
        return mean, std


class OnnxHead(HeadWeights):
    """The exported delta head: the weights it was exported from (for counting and saving), its
    answers from onnxruntime."""

    def __init__(self, folder: str | Path, arrays: dict[str, np.ndarray], manifest: dict | None = None) -> None:
        super().__init__(arrays)
        meta = (manifest or read_export(folder))["head"]
        self._session = _session(Path(folder) / meta["file"])

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, np.float32)
        if not len(x):
            return np.zeros(0)
        # One row per call, as the online module asks (the export's batch is one row).
        return np.array([self._session.run(None, {"features": row[None]})[0][0] for row in x], float)
