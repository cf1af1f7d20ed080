"""Where episodes run: in this process, a local pool of spawned processes, or Ray.

Every executor calls :func:`run_episode` in the worker, which writes the episode's part
itself, so a finished episode is stored even if the driver dies.

Workers are spawned, never forked: a process that has made a GL context must not fork
renderers. Each worker runs one episode at a time on one core: torch and OpenMP on one
thread, and Mesa's software rasteriser (llvmpipe) on the calling thread
(``LP_NUM_THREADS=0``; with one rasteriser thread, handing it each frame made a frame about
20 % slower). Left at their defaults, every worker would start as many threads as the
machine has cores, and two workers on two cores ran slower together than one alone
(``racf bench-loop`` measured 0.25 scaling efficiency). Ray workers get ``MUJOCO_GL`` and the
same settings through their runtime env.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager, nullcontext
from typing import Callable, Iterator

from racf.experiments.episode import TrialSpec

__all__ = ["BACKENDS", "SINGLE_THREAD_ENV", "CodeChangedError", "single_thread", "spawn_pool", "run_episode", "local_executor",
           "ray_executor", "ray_session", "backend_session", "executor"]

#: Where episodes can run.
BACKENDS = ("local", "ray")
#: Environment variables that keep a worker's libraries on one thread (read when they start).
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "LP_NUM_THREADS": "0"}


def single_thread() -> None:
    """Pins this process's numeric and rendering libraries to one thread (call before rendering)."""
    os.environ.update(SINGLE_THREAD_ENV)
    import torch

    torch.set_num_threads(1)


def spawn_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned, single-threaded processes."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"), initializer=single_thread)


class CodeChangedError(ValueError):
    """A worker's episode id differs from the one the batch computed: racf's code, or a
    plug-in's, changed on disk while the batch ran, so the stored episode would not be the
    one asked for."""


def run_episode(spec: TrialSpec, out: str, log_steps: bool = False, logs_dir: str = "logs",
                rerun: bool = False, expected_id: str | None = None) -> dict:
    """Runs one episode and stores it in the :class:`ResultStore` at ``out``; returns its row.

    Args:
        spec: the episode.
        out: the store's folder.
        log_steps: also keep the per-step log (and run the ``d_clean`` diagnostic pass it
            carries; the row is the same without it).
        logs_dir: the store's log folder.
        rerun: also record the episode to ``<logs_dir>/<id>.rrd`` (implies ``log_steps``).
        expected_id: the id the batch computed; a worker that computes another refuses to run
            (:class:`CodeChangedError`).
    """
    from racf.experiments.sweeps.store import ResultStore
    from racf.experiments.viz.rerun_log import recorded_trial

    if expected_id is not None and spec.trial_id != expected_id:
        raise CodeChangedError(f"racf's code or a plug-in changed on disk while the batch ran (episode "
                               f"{expected_id} is now {spec.trial_id}); run the command again")
    store = ResultStore(out, logs_dir)
    log_steps = log_steps or rerun
    result, log = recorded_trial(spec, store.log_path(spec.trial_id, ".rrd") if rerun else None,
                                 f"racf trial {spec.trial_id}", clean_pass=log_steps)
    row = {**result.to_dict(), "attack": "+".join(spec.attacks) or "none", "rho_set": spec.rho[0],
           "t_atk_set": spec.t_atk[0], "attack_params": params_label(spec.attack_params),
           **{f"param_{key}": value for table in spec.attack_params.values() for key, value in table.items()}}
    row = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}
    store.write(spec.trial_id, row, log if log_steps else None)
    return row


def params_label(params: dict) -> str:
    """``stealth_ramp.rate_mps=3.0``-style label of an episode's attack settings ('' without any)."""
    return " ".join(f"{name}.{key}={value}" for name, table in sorted(params.items())
                    for key, value in sorted(table.items()))


def local_executor(specs: list[TrialSpec], out: str, workers: int, **episode) -> Iterator[dict]:
    """Rows as episodes finish, from ``workers`` spawned processes (in this process for 1).
    ``episode`` holds :func:`run_episode`'s keywords."""
    if workers <= 1:
        for spec in specs:
            yield run_episode(spec, out, **episode)
        return
    with spawn_pool(workers) as pool:
        futures = [pool.submit(run_episode, spec, out, expected_id=spec.trial_id, **episode) for spec in specs]
        for future in as_completed(futures):
            yield future.result()


@contextmanager
def ray_session(workers: int, address: str | None = None) -> Iterator[None]:
    """Ray for the episodes, shut down after if this call started it.

    With ``address``, joins that cluster. Without, always starts a local Ray of its own with
    ``workers`` CPUs (``address="local"``), the dashboard, usage stats and token auth off: it
    never joins a cluster that happens to run on the machine, or one that died and left its
    address file behind. An already initialised Ray is used as it is.
    """
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    import ray

    from racf.plugins import PLUGIN_ENV

    env_vars = {"MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"), "RAY_USAGE_STATS_ENABLED": "0",
                "RAY_AUTH_MODE": "disabled", **SINGLE_THREAD_ENV}
    if os.environ.get(PLUGIN_ENV):  # --plugin files: a cluster's workers load them too (same path on every node)
        env_vars[PLUGIN_ENV] = os.environ[PLUGIN_ENV]
    started = False
    if not ray.is_initialized():
        kwargs = ({"address": address} if address else
                  {"address": "local", "num_cpus": workers, "include_dashboard": False})
        ray.init(runtime_env={"env_vars": env_vars}, log_to_driver=False, **kwargs)
        started = True
    try:
        yield
    finally:
        if started:
            ray.shutdown()


def backend_session(backend: str, workers: int, address: str | None = None):
    """One Ray for several batches (``backend == "ray"``): their executors use it as it is."""
    return ray_session(workers, address) if backend == "ray" else nullcontext()


def ray_executor(specs: list[TrialSpec], out: str, workers: int, address: str | None = None,
                 **episode) -> Iterator[dict]:
    """Rows as episodes finish on Ray: a cluster at ``address``, or a local Ray with ``workers`` CPUs."""
    import ray

    with ray_session(workers, address):
        remote: Callable = ray.remote(num_cpus=1)(run_episode)
        pending = [remote.remote(spec, out, expected_id=spec.trial_id, **episode) for spec in specs]
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            yield ray.get(ready[0])


def executor(backend: str, specs: list[TrialSpec], out: str, workers: int, address: str | None = None,
             **episode) -> Iterator[dict]:
    """The rows of ``specs`` run on ``backend`` (one of ``BACKENDS``), as they finish."""
    if backend == "ray":
        return ray_executor(specs, out, workers, address, **episode)
    if address is not None:
        raise ValueError("--address joins a Ray cluster: it needs --backend ray")
    return local_executor(specs, out, workers, **episode)
