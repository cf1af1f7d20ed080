"""Where episodes run: in this process, a local pool of spawned processes, or Ray.

Every executor calls :func:`run_episode` in the worker, which writes the episode's part
itself, so a finished episode is stored even if the driver dies.

Workers are spawned, never forked: a process that has made a GL context must not fork
renderers. Each worker runs one episode at a time on one core: torch and OpenMP on one
thread, and Mesa's software rasteriser (llvmpipe) on the calling thread
(``LP_NUM_THREADS=0``; with one rasteriser thread, handing it each frame made a frame about
20 % slower). Left at their defaults, every worker would start as many threads as the
machine has cores, and two workers on two cores ran slower together than one alone
(``racf bench loop`` measured 0.25 scaling efficiency). Ray workers get ``MUJOCO_GL`` and the
same settings through their runtime env.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import signal
from collections import Counter, deque
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager, nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Iterator

from racf.errors import EpisodeFailed, UserError

if TYPE_CHECKING:  # the spec's module imports the simulator: a command's --help must not wait for it
    from racf.experiments.episode import TrialSpec

__all__ = ["BACKENDS", "SINGLE_THREAD_ENV", "CodeChangedError", "Workers", "check_backend", "single_thread",
           "spawn_pool", "run_episode", "episode_task", "local_executor", "ray_executor", "ray_session",
           "backend_session", "executor"]

#: Where episodes can run.
BACKENDS = ("local", "ray")
#: Environment variables that keep a worker's libraries on one thread (read when they start).
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "LP_NUM_THREADS": "0"}


def single_thread() -> None:
    """Pins this process's numeric and rendering libraries to one thread (call before rendering)."""
    os.environ.update(SINGLE_THREAD_ENV)
    import cv2
    import torch

    torch.set_num_threads(1)
    cv2.setNumThreads(1)  # OpenCV's own pool otherwise starts a thread per core (same detections: tested)


def spawn_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned, single-threaded processes that leave Ctrl-C to the driver."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"), initializer=_worker_init)


class CodeChangedError(UserError):
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
    from racf.experiments.episode.rerun_log import recorded_trial

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


def episode_task(spec: TrialSpec, out: str, **episode) -> dict:
    """:func:`run_episode` as a worker runs it: ``{"row": row}``, or ``{"failure": Failure}`` when
    the episode's code raised (a user's plug-in, or a bug of racf's). A failure is returned, not
    raised, so that one episode's fault never aborts the batch. A :class:`~racf.errors.UserError`
    is ``{"stop": message}``: what it names (a defence service that no longer answers, keys it
    refuses) fails every episode alike, so the batch stops. :class:`CodeChangedError` is raised:
    the batch must stop."""
    try:
        return {"row": run_episode(spec, out, **episode)}
    except CodeChangedError:
        raise
    except UserError as err:  # not this episode's fault but the batch's (a service gone, keys refused): stop
        return {"stop": str(err)}
    except Exception as err:  # the fault of the code an episode runs, reported by episode, never a traceback
        from racf.experiments.sweeps.failures import describe

        return {"failure": describe(spec, err)}


def _worker_init() -> None:
    """A pool worker: one thread, and deaf to Ctrl-C (the terminal sends SIGINT to the whole
    process group; the driver alone decides, and stops its workers itself)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    single_thread()


def check_backend(backend: str, workers: int, address: str | None = None) -> None:
    """UserError names a backend, worker count or address racf cannot run episodes on."""
    if backend not in BACKENDS:
        raise UserError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if not (isinstance(workers, int) and workers >= 1):
        raise UserError(f"workers must be an int >= 1, got {workers!r}")
    if address is not None and backend != "ray":
        raise UserError("--address joins a Ray cluster: it needs --backend ray")


class Workers:
    """Where a batch's episodes run, started once and kept for several batches (a context manager).

    ``backend="local"``: ``workers`` spawned processes (this process for 1); ``"ray"``: a Ray
    cluster at ``address``, or a local Ray of ``workers`` CPUs. :meth:`run` yields each episode's
    outcome (:func:`episode_task`) as it finishes.

    A local worker that dies mid-episode (SIGKILL, out of memory) breaks the pool: a new pool
    starts and the episodes it was running run again (those that had stored their part are
    read back, not run). Which of them killed its worker cannot be told, so when several were
    running each runs again alone: a bystander is not blamed for another's death. An episode that
    was running when workers died twice is reported as a failure. Ray retries a task whose worker died once (``max_retries=1``) on another worker.

    Leaving the block on an exception (Ctrl-C included) kills the workers at once: nothing
    pending starts, and a killed episode stores nothing (parts are written atomically).
    """

    def __init__(self, backend: str = "local", workers: int = 2, address: str | None = None) -> None:
        check_backend(backend, workers, address)
        self.backend, self.workers, self.address = backend, workers, address
        self._pool: ProcessPoolExecutor | None = None
        self._ray = None
        self._refs: list = []

    def __enter__(self) -> "Workers":
        if self.backend == "ray":
            self._ray = ray_session(self.workers, self.address)
            self._ray.__enter__()
        return self

    def __exit__(self, kind, value, tb) -> None:
        if kind is not None:
            self.stop()
        elif self._pool is not None:
            self._pool.shutdown(wait=True)
        self._pool = None
        if self._ray is not None:
            self._ray.__exit__(None, None, None)
            self._ray = None

    def run(self, specs: list[TrialSpec], out: str, **episode) -> Iterator[dict]:
        """The outcome of each of ``specs`` as it finishes; ``episode`` holds :func:`run_episode`'s keywords."""
        if self.backend == "ray":
            yield from self._run_ray(specs, out, **episode)
        elif self.workers <= 1:
            for spec in specs:
                yield episode_task(spec, out, **episode)
        else:
            yield from self._run_local(specs, out, **episode)

    def stop(self) -> None:
        """Kills the workers now: pending episodes never start, running ones store nothing."""
        if self._pool is not None:
            for process in list((getattr(self._pool, "_processes", None) or {}).values()):
                process.kill()
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
        if self._refs:
            import ray

            for ref in self._refs:
                ray.cancel(ref, force=True)
            self._refs = []

    def _run_local(self, specs: list[TrialSpec], out: str, **episode) -> Iterator[dict]:
        # At most `workers` episodes are handed out at a time, so those in flight when a worker
        # dies are known, and an interrupt has nothing queued in the pool to drain.
        queue, running, deaths = deque(specs), {}, Counter()
        suspects: set[str] = set()  # in flight together when a worker died: each runs again alone
        while queue or running:
            if self._pool is None:
                self._pool = spawn_pool(self.workers)
            while queue and len(running) < self.workers:
                alone = queue[0].trial_id in suspects or any(s.trial_id in suspects for s in running.values())
                if alone and running:
                    break
                spec = queue.popleft()
                try:
                    future = self._pool.submit(episode_task, spec, out, expected_id=spec.trial_id, **episode)
                except BrokenProcessPool:  # a worker died since the last wait: the futures in flight will say so
                    queue.appendleft(spec)  # never started: not a death of its own
                    if not running:  # nothing in flight to report it: a new pool
                        self._pool.shutdown(wait=False, cancel_futures=True)
                        self._pool = None
                    break
                running[future] = spec
            if not running:
                continue
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            lost = []
            for future in done:
                spec = running.pop(future)
                try:
                    yield future.result()
                except BrokenProcessPool:
                    lost.append(spec)
            if lost:  # a worker died: every episode in flight is lost with the pool
                lost += list(running.values())
                running.clear()
                self._pool.shutdown(wait=False, cancel_futures=True)
                self._pool = None
                if len(lost) > 1:
                    suspects.update(s.trial_id for s in lost)
                yield from self._after_death(lost, queue, deaths, out, episode.get("logs_dir", "logs"))

    @staticmethod
    def _after_death(lost: list[TrialSpec], queue: deque, deaths: Counter, out: str, logs_dir: str) -> Iterator[dict]:
        from racf.experiments.sweeps.failures import worker_died
        from racf.experiments.sweeps.store import ResultStore

        store = ResultStore(out, logs_dir)
        done = store.done_ids()
        for spec in reversed(lost):
            if spec.trial_id in done:  # it stored its part before the pool broke
                yield {"row": store.rows([spec.trial_id]).iloc[0].to_dict()}
                continue
            deaths[spec.trial_id] += 1
            if deaths[spec.trial_id] >= 2:
                yield {"failure": worker_died(spec)}
            else:
                queue.appendleft(spec)  # retried first, on a new worker

    def _run_ray(self, specs: list[TrialSpec], out: str, **episode) -> Iterator[dict]:
        import ray
        from ray.exceptions import WorkerCrashedError

        from racf.experiments.sweeps.failures import worker_died

        remote: Callable = ray.remote(num_cpus=1, max_retries=1)(episode_task)
        refs = {remote.remote(spec, out, expected_id=spec.trial_id, **episode): spec for spec in specs}
        self._refs = list(refs)
        while refs:
            ready, _ = ray.wait(list(refs), num_returns=1)
            spec = refs.pop(ready[0])
            self._refs = list(refs)
            try:
                yield ray.get(ready[0])
            except WorkerCrashedError:  # it died on two workers
                yield {"failure": worker_died(spec)}


def local_executor(specs: list[TrialSpec], out: str, workers: int, **episode) -> Iterator[dict]:
    """Rows as episodes finish, from ``workers`` spawned processes (in this process for 1).
    ``episode`` holds :func:`run_episode`'s keywords. A failed episode raises (:class:`EpisodeFailed`)."""
    with Workers("local", workers) as pool:
        yield from _rows(pool.run(specs, out, **episode), len(specs), out)


def _rows(outcomes: Iterator[dict], total: int, out: str) -> Iterator[dict]:
    """The rows of the outcomes; the first failure stops them (its traceback logged under ``out``)."""
    from racf.experiments.sweeps.failures import append_log

    for outcome in outcomes:
        if "failure" in outcome:
            raise EpisodeFailed([outcome["failure"]], 0, total, append_log(Path(out), outcome["failure"], first=True))
        yield outcome["row"]


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
    with Workers("ray", workers, address) as pool:
        yield from _rows(pool.run(specs, out, **episode), len(specs), out)


def executor(backend: str, specs: list[TrialSpec], out: str, workers: int, address: str | None = None,
             **episode) -> Iterator[dict]:
    """The rows of ``specs`` run on ``backend`` (one of ``BACKENDS``), as they finish."""
    if backend == "ray":
        return ray_executor(specs, out, workers, address, **episode)
    if address is not None:
        raise UserError("--address joins a Ray cluster: it needs --backend ray")
    return local_executor(specs, out, workers, **episode)
