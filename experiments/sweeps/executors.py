"""Where a sweep's episodes run: a local pool of spawned processes, or Ray.

Both call :func:`run_episode` in the worker, which writes the episode's part itself, so a
finished episode is stored even if the driver dies. Workers are spawned, never forked (a
process that has made a GL context must not fork renderers), and Ray workers get
``MUJOCO_GL`` through their runtime env.
"""

from __future__ import annotations

import os
from concurrent.futures import as_completed
from contextlib import contextmanager
from typing import Callable, Iterator

from experiments.episode import TrialSpec
from experiments.workers import SINGLE_THREAD_ENV, spawn_pool

__all__ = ["run_episode", "local_executor", "ray_executor", "ray_session", "BACKENDS"]

BACKENDS = ("local", "ray")


def run_episode(spec: TrialSpec, out: str, log_steps: bool = False) -> dict:
    """Runs one episode and stores it; returns its row."""
    import math

    from experiments.episode import run_trial
    from experiments.sweeps.store import ResultStore

    # The d_clean diagnostic pass is for per-step logs; the row is the same without it.
    result, log = run_trial(spec, clean_pass=log_steps)
    row = {**result.to_dict(), "attack": "+".join(spec.attacks) or "none", "rho_set": spec.rho[0],
           "t_atk_set": spec.t_atk[0]}
    row = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}
    ResultStore(out).write(spec.trial_id, row, log if log_steps else None)
    return row


def local_executor(specs: list[TrialSpec], out: str, workers: int, log_steps: bool) -> Iterator[dict]:
    """Rows as episodes finish, from ``workers`` spawned processes (in-process for 1)."""
    if workers <= 1:
        for spec in specs:
            yield run_episode(spec, out, log_steps)
        return
    with spawn_pool(workers) as pool:
        futures = [pool.submit(run_episode, spec, out, log_steps) for spec in specs]
        for future in as_completed(futures):
            yield future.result()


@contextmanager
def ray_session(workers: int, address: str | None = None) -> Iterator[None]:
    """Ray for the episodes: joins the cluster at ``address``, or starts a local Ray with
    ``workers`` CPUs and the dashboard, usage stats and token auth off (and stops it after).
    An already initialised Ray is used as it is."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    import ray

    env_vars = {"MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"), "RAY_USAGE_STATS_ENABLED": "0",
                **SINGLE_THREAD_ENV}
    started = False
    if not ray.is_initialized():
        kwargs = {"address": address} if address else {"num_cpus": workers, "include_dashboard": False}
        ray.init(runtime_env={"env_vars": env_vars}, log_to_driver=False, **kwargs)
        started = True
    try:
        yield
    finally:
        if started:
            ray.shutdown()


def ray_executor(specs: list[TrialSpec], out: str, workers: int, log_steps: bool,
                 address: str | None = None) -> Iterator[dict]:
    """Rows as episodes finish on Ray: a cluster at ``address``, or a local Ray with ``workers`` CPUs."""
    import ray

    with ray_session(workers, address):
        remote: Callable = ray.remote(num_cpus=1)(run_episode)
        pending = [remote.remote(spec, out, log_steps) for spec in specs]
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            yield ray.get(ready[0])
