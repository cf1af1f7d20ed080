"""The one path for every batch of episodes: check everything first, skip stored episodes, run
the rest on an executor, and read the rows back. Sweeps, ``racf trials``, the paper's table, the
attack study and dataset collection all run through :func:`run_episodes`."""

from __future__ import annotations

import time
from pathlib import Path

import pandas as pd

from racf.experiments.episode import TrialSpec
from racf.experiments.sweeps.executors import BACKENDS, executor
from racf.experiments.sweeps.report import write_report
from racf.experiments.sweeps.spec import SweepSpec
from racf.experiments.sweeps.store import ResultStore
from racf.experiments.sweeps.summary import summarize_settings

__all__ = ["run_episodes", "run_sweep"]


def run_episodes(specs: list[TrialSpec], store: ResultStore, backend: str = "local", workers: int = 2,
                 address: str | None = None, log_steps: bool = False, rerun: bool = False,
                 progress: bool = True, desc: str = "episodes") -> tuple[pd.DataFrame, int]:
    """Runs (or resumes) ``specs`` into ``store``; returns their rows in spec order and how many ran.

    Episodes whose part is in the store are reused, not run again. With ``rerun``, every
    episode that runs is also recorded to ``<store.logs>/<id>.rrd`` (reused ones are not
    recorded again).
    """
    from tqdm import tqdm

    _check(backend, workers)
    ids = [spec.trial_id for spec in specs]
    if len(set(ids)) != len(ids):
        raise ValueError("the batch lists the same episode twice; vary the seed, repeats or the space")
    store.prepare()
    done = store.done_ids()
    todo = [spec for spec, i in zip(specs, ids) if i not in done]
    bar = tqdm(total=len(specs), initial=len(specs) - len(todo), desc=desc, unit="episode", disable=not progress,
               smoothing=0.1)
    if todo:
        for _ in executor(backend, todo, str(store.out), workers, address, log_steps=log_steps,
                          logs_dir=store.logs.name, rerun=rerun):
            bar.update()
    bar.close()
    return store.rows(ids), len(todo)


def _check(backend: str, workers: int) -> None:
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if not (isinstance(workers, int) and workers >= 1):
        raise ValueError(f"workers must be an int >= 1, got {workers!r}")


def run_sweep(spec: SweepSpec, spec_text: str, out: str | Path, backend: str = "local", workers: int = 2,
              address: str | None = None, progress: bool = True) -> dict:
    """Runs (or resumes) ``spec`` into ``out`` and writes its report; returns ``{n, done, reused, wall_s, scr}``."""
    t0 = time.perf_counter()
    _check(backend, workers)
    episodes = spec.episodes()
    store = ResultStore(out)
    store.prepare(spec_text, spec.spec_hash)
    frame, ran = run_episodes(episodes, store, backend, workers, address, log_steps=spec.log_steps,
                              progress=progress, desc=f"sweep {spec.name}")
    frame = frame.sort_values("trial_id", ignore_index=True)
    write_report(frame, Path(out), f"{spec.name} ({spec.sensor_profile} sensors, {spec.sign_geometry} signs, "
                                   f"{spec.detector} detector)")
    return {"n": len(episodes), "done": ran, "reused": len(episodes) - ran, "wall_s": time.perf_counter() - t0,
            "scr": {k: v["scr"] for k, v in summarize_settings(frame).items()}}
