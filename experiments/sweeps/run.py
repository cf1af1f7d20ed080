"""Runs a sweep: checks everything first, skips stored episodes, runs the rest, reports."""

from __future__ import annotations

import time
from pathlib import Path

from experiments.sweeps.executors import BACKENDS, local_executor, ray_executor
from experiments.sweeps.report import summarize, write_report
from experiments.sweeps.spec import SweepSpec
from experiments.sweeps.store import ResultStore

__all__ = ["run_sweep"]


def run_sweep(spec: SweepSpec, spec_text: str, out: str | Path, backend: str = "local", workers: int = 2,
              address: str | None = None, progress: bool = True) -> dict:
    """Runs (or resumes) ``spec`` into ``out``; returns ``{n, done, reused, wall_s, scr}``."""
    from tqdm import tqdm

    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if not (isinstance(workers, int) and workers >= 1):
        raise ValueError(f"workers must be an int >= 1, got {workers!r}")
    t0 = time.perf_counter()
    episodes = spec.episodes()
    ids = [e.trial_id for e in episodes]
    if len(set(ids)) != len(ids):
        raise ValueError("the sweep lists the same episode twice; vary seed, repeats or the space")
    store = ResultStore(out)
    store.prepare(spec_text, spec.spec_hash)
    done = store.done_ids()
    todo = [e for e, i in zip(episodes, ids) if i not in done]
    reused = len(episodes) - len(todo)
    bar = tqdm(total=len(episodes), initial=reused, desc=f"sweep {spec.name}", unit="episode", disable=not progress,
               smoothing=0.1)
    if todo:
        rows = (ray_executor(todo, str(out), workers, spec.log_steps, address) if backend == "ray"
                else local_executor(todo, str(out), workers, spec.log_steps))
        for _ in rows:
            bar.update()
    bar.close()
    frame = store.rows()
    frame = frame[frame["trial_id"].isin(set(ids))].reset_index(drop=True)
    write_report(frame, Path(out), spec.name)
    return {"n": len(episodes), "done": len(todo), "reused": reused, "wall_s": time.perf_counter() - t0,
            "scr": {k: v["scr"] for k, v in summarize(frame).items()}}
