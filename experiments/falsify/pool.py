"""Where a search's episodes run: one set of workers (local spawned processes or Ray) kept for the
whole search, fed in rounds. Every episode is an ordinary one: stored in a :class:`ResultStore` by
its id, so a resumed search, or another sampler that asks for the same episode, reads it back.
A round runs through :func:`~racf.experiments.sweeps.run.run_episodes`, so its episodes are
checked, interrupted and reported as any batch's."""

from __future__ import annotations

import pandas as pd

from racf.experiments.episode import TrialSpec
from racf.experiments.sweeps.executors import Workers
from racf.experiments.sweeps.run import run_episodes
from racf.experiments.sweeps.store import ResultStore

__all__ = ["EpisodePool"]


class EpisodePool:
    """Runs rounds of episodes into ``store`` on ``workers`` processes (``backend`` local or ray).

    Use as a context manager: the processes (or Ray) start once and stop at the end.
    """

    def __init__(self, store: ResultStore, backend: str = "local", workers: int = 2, address: str | None = None,
                 rerun: bool = False) -> None:
        self._workers = Workers(backend, workers, address)  # checks them
        self.store, self.rerun = store, rerun
        self.ran = 0

    def __enter__(self) -> "EpisodePool":
        self.store.prepare()
        self._workers.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        self._workers.__exit__(*exc)

    def run(self, specs: list[TrialSpec]) -> pd.DataFrame:
        """The rows of ``specs`` in their order: stored ones read back, the others run now."""
        unique = list({spec.trial_id: spec for spec in specs}.values())  # an episode asked twice runs once
        _, ran = run_episodes(unique, self.store, rerun=self.rerun, progress=False, pool=self._workers)
        self.ran += ran
        return self.store.rows([spec.trial_id for spec in specs])
