"""``racf bench odca-latency``: per-step time of the online ODCA module on the CPU with the shipped prior.

Feeds a 50 Hz approach series (depth with noise, dropouts and a blackout, LiDAR, speed)
through ``ODCA.step`` and times every call. The prior forecasts every ``refresh_steps``
steps, so the median is the cheap step and the p99 the step that runs the prior.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["odca_latency"]


def odca_latency(steps: int = 2000, seed: int = 0, threads: int = 1) -> dict:
    import torch

    from racf.odca import ODCA
    from racf.odca.synthetic import approach_curve

    torch.set_num_threads(threads)
    rng = np.random.default_rng(seed)
    model = ODCA.load()
    depth = np.concatenate([approach_curve(rng, 250) for _ in range(steps // 250 + 1)])[:steps]
    depth[rng.random(steps) < 0.1] = np.nan
    lidar = depth + 0.12 + rng.normal(0, 0.01, steps)
    times = np.empty(steps)
    for t in range(steps):
        t0 = time.perf_counter()
        model.step(depth=float(depth[t]), confidence=0.9, lidar=float(lidar[t]), speed=1.0)
        times[t] = time.perf_counter() - t0
    ms = times[20:] * 1000  # the first calls warm caches up
    return {"steps": int(len(ms)), "median_ms": float(np.median(ms)), "p99_ms": float(np.percentile(ms, 99)),
            "mean_ms": float(ms.mean()), "max_ms": float(ms.max()), "refresh_steps": model.config.refresh_steps,
            "threads": threads, "paper_offboard_ms": 49.0}
