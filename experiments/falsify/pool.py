"""Where a search's episodes run: one pool (local spawned processes or Ray) kept for the whole
search, fed in rounds. Every episode is an ordinary one: stored in a :class:`ResultStore` by its
id, so a resumed search, or another sampler that asks for the same episode, reads it back."""

from __future__ import annotations

from concurrent.futures import as_completed
from contextlib import ExitStack

import pandas as pd

from racf.experiments.episode import TrialSpec
from racf.experiments.sweeps.executors import BACKENDS, ray_session, run_episode, spawn_pool
from racf.experiments.sweeps.store import ResultStore

__all__ = ["EpisodePool"]


class EpisodePool:
    """Runs rounds of episodes into ``store`` on ``workers`` processes (``backend`` local or ray).

    Use as a context manager: the processes (or Ray) start once and stop at the end.
    """

    def __init__(self, store: ResultStore, backend: str = "local", workers: int = 2, address: str | None = None,
                 rerun: bool = False) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        if not (isinstance(workers, int) and workers >= 1):
            raise ValueError(f"workers must be an int >= 1, got {workers!r}")
        if address is not None and backend != "ray":
            raise ValueError("--address joins a Ray cluster: it needs --backend ray")
        self.store, self.backend, self.workers, self.address, self.rerun = store, backend, workers, address, rerun
        self._stack = ExitStack()
        self._pool = None
        self._remote = None
        self.ran = 0

    def __enter__(self) -> "EpisodePool":
        self.store.prepare()
        if self.backend == "ray":
            import ray

            self._stack.enter_context(ray_session(self.workers, self.address))
            self._remote = ray.remote(num_cpus=1)(run_episode)
        elif self.workers > 1:
            self._pool = self._stack.enter_context(spawn_pool(self.workers))
        return self

    def __exit__(self, *exc) -> None:
        self._stack.close()

    def run(self, specs: list[TrialSpec]) -> pd.DataFrame:
        """The rows of ``specs`` in their order: stored ones read back, the others run now."""
        ids = [spec.trial_id for spec in specs]
        done = self.store.done_ids()
        todo = {i: spec for spec, i in zip(specs, ids) if i not in done}  # an episode asked twice runs once
        kwargs = {"logs_dir": str(self.store.logs.relative_to(self.store.out)), "rerun": self.rerun}
        out = str(self.store.out)
        if todo and self._remote is not None:
            import ray

            ray.get([self._remote.remote(spec, out, expected_id=i, **kwargs) for i, spec in todo.items()])
        elif todo and self._pool is not None:
            futures = [self._pool.submit(run_episode, spec, out, expected_id=i, **kwargs) for i, spec in todo.items()]
            for future in as_completed(futures):
                future.result()
        else:
            for i, spec in todo.items():
                run_episode(spec, out, expected_id=i, **kwargs)
        self.ran += len(todo)
        return self.store.rows(ids)
