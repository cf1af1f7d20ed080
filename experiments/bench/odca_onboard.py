"""``racf bench odca-onboard``: ODCA exported (onnxruntime) against ODCA in PyTorch, step by step.

Both models step through the offline benchmark's test series (the dataset's by-series test
split, clean and under each corruption preset, draw 0), as the car would run them, and every
output is compared: the largest difference in d_fused, and the steps where the gate chose
another source. Each step of each is timed on one thread; the table puts p50, p99 and max beside
the 20 ms control period (a step that runs the prior is the slow one).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

__all__ = ["compare_onboard", "CONTROL_PERIOD_MS"]

CONTROL_PERIOD_MS = 20.0


def _series(dataset: Path, presets: tuple[str, ...]):
    """(preset, one run ODCA makes afresh) over the test split: clean (the depth is ``d_clean``) and
    each preset's draw 0, cut where ``ODCA.run`` cuts them (a series, a slot)."""
    from racf.experiments.data.dataset import load_dataset
    from racf.odca.series import segments

    ds = load_dataset(dataset, split="by_series")
    for preset in presets:
        if preset == "clean":
            frame = ds.clean("test").assign(d_meas=lambda f: f["d_clean"], c_meas=lambda f: f["c_clean"])
        else:
            frame = ds.corrupted(preset, "test", 0).reset_index(drop=True)
        for rows in segments(frame):
            yield preset, frame.iloc[rows]


def _steps(model, series) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """d_fused, the gate's source and the time of each step of ``series`` through ``model``."""
    from racf.odca.series import _optional

    model.reset()
    n = len(series)
    out, source, ms = np.empty(n), np.empty(n), np.empty(n)
    cols = {k: series[k].to_numpy(float) for k in ("d_meas", "c_meas", "lidar", "speed")}
    yaw, bearing = _optional(series, "yaw_rate", 0.0), _optional(series, "bearing", np.nan)
    size, size_std = _optional(series, "d_size", np.nan), _optional(series, "size_std", np.nan)
    for t in range(n):
        start = time.perf_counter()
        r = model.step(depth=cols["d_meas"][t], confidence=cols["c_meas"][t], lidar=cols["lidar"][t],
                       speed=cols["speed"][t], yaw_rate=yaw[t], bearing=bearing[t], size=size[t], size_std=size_std[t])
        ms[t] = (time.perf_counter() - start) * 1000.0
        out[t], source[t] = r.d_fused, r.source
    return out, source, ms


def _latency(ms: np.ndarray) -> dict:
    return {"p50_ms": float(np.percentile(ms, 50)), "p99_ms": float(np.percentile(ms, 99)), "max_ms": float(ms.max()),
            "over_period": int((ms > CONTROL_PERIOD_MS).sum())}


def compare_onboard(dataset: Path, export: Path | None = None, presets: tuple[str, ...] = ("clean", "weak", "mid", "strong"),
                    progress=None) -> dict:
    """The exported ODCA (``export``; default: the shipped export) against the PyTorch path on the
    benchmark's test series; both on one thread."""
    import torch

    from racf.odca import ODCA

    torch.set_num_threads(1)
    torch_model, onnx_model = ODCA.load(), ODCA.load(export, runtime="onnx")
    diffs, sources, steps = [], 0, 0
    times = {"torch": [], "onnx": []}
    per_preset: dict = {}
    for preset, series in _series(dataset, presets):
        a, src_a, ms_a = _steps(torch_model, series)
        b, src_b, ms_b = _steps(onnx_model, series)
        both = np.isfinite(a) & np.isfinite(b)
        if not np.array_equal(np.isfinite(a), np.isfinite(b)):
            raise AssertionError(f"a series of {preset}: the two paths disagree on where there is a target")
        diff = float(np.max(np.abs(a[both] - b[both]))) if both.any() else 0.0
        diffs.append(diff)
        per_preset[preset] = max(per_preset.get(preset, 0.0), diff)
        sources += int((src_a != src_b).sum())
        steps += len(series)
        times["torch"].append(ms_a[20:])
        times["onnx"].append(ms_b[20:])
        if progress is not None:
            progress(len(series))
    return {"steps": steps, "series": len(diffs), "max_abs_diff_m": max(diffs) if diffs else math.nan,
            "max_abs_diff_m_by_preset": per_preset, "source_changes": sources,
            "latency": {k: _latency(np.concatenate(v)) for k, v in times.items()},
            "control_period_ms": CONTROL_PERIOD_MS, "dataset": str(dataset)}
