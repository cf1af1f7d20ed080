"""The one path for every batch of episodes: check everything first, skip stored episodes, run
the rest on an executor, and read the rows back. Sweeps, ``racf trials``, the paper's table, the
attack study and dataset collection all run through :func:`run_episodes`."""

from __future__ import annotations

import sys
import time
from contextlib import nullcontext
from pathlib import Path

import pandas as pd

from racf.errors import EpisodeFailed, Failure, Interrupted, UserError
from racf.experiments.episode import TrialSpec
from racf.experiments.episode.preflight import check_specs
from racf.experiments.sweeps.executors import Workers, check_backend
from racf.experiments.sweeps.failures import LOG_NAME, append_log
from racf.experiments.sweeps.report import write_report
from racf.experiments.sweeps.spec import SweepSpec
from racf.experiments.sweeps.store import ResultStore
from racf.experiments.sweeps.summary import summarize_settings

__all__ = ["run_episodes", "run_sweep"]


def run_episodes(specs: list[TrialSpec], store: ResultStore, backend: str = "local", workers: int = 2,
                 address: str | None = None, log_steps: bool = False, rerun: bool = False,
                 progress: bool = True, desc: str = "episodes",
                 pool: Workers | None = None) -> tuple[pd.DataFrame, int]:
    """Runs (or resumes) ``specs`` into ``store``; returns their rows in spec order and how many ran.

    Everything the specs name is built once first (estimators with their options, the attack
    wrappers with their parameters and schedules), so a value racf or a plug-in refuses stops
    the batch before any episode (:class:`~racf.errors.UserError`). Episodes whose part is in
    the store are reused, not run again. With ``rerun``, every episode that runs is also
    recorded to ``<store.logs>/<id>.rrd``. ``pool`` runs the batch on workers already started
    (else a :class:`Workers` of ``backend``, ``workers`` and ``address`` is started for it).

    Raises:
        EpisodeFailed: after the batch, if episodes raised (a plug-in's fault): the batch goes
            on past a failed episode, so every other one is stored; the tracebacks are in
            ``<store.out>/failures.log``.
        Interrupted: Ctrl-C or SIGTERM: the workers are killed at once; what is stored stays.
    """
    from tqdm import tqdm

    ids = [spec.trial_id for spec in specs]
    if len(set(ids)) != len(ids):
        raise UserError("the batch lists the same episode twice; vary the seed, repeats or the space")
    check_specs(specs)
    store.prepare()
    done = store.done_ids()
    todo = [spec for spec, i in zip(specs, ids) if i not in done]
    if progress and len(todo) < len(specs):
        print(f"{desc}: {len(specs) - len(todo)} of {len(specs)} episodes are stored in {store.out} already "
              f"(same spec, configs and code): reused, not run again", file=sys.stderr)
    bar = tqdm(total=len(specs), initial=len(specs) - len(todo), desc=desc, unit="episode", disable=not progress,
               smoothing=0.1)
    failures: list[Failure] = []
    try:
        with nullcontext(pool) if pool is not None else Workers(backend, workers, address) as running:
            if todo:
                for outcome in running.run(todo, str(store.out), log_steps=log_steps,
                                           logs_dir=str(store.logs.relative_to(store.out)),
                                           rerun=rerun):
                    if "stop" in outcome:  # leaving the block kills the workers; what is stored stays
                        raise _Stopped(outcome["stop"])
                    if "failure" in outcome:
                        append_log(store.out, outcome["failure"], first=not failures)
                        failures.append(outcome["failure"])
                        bar.set_postfix(failed=len(failures))
                    bar.update()
    except KeyboardInterrupt:
        bar.close()
        raise Interrupted(len(set(ids) & store.done_ids()), len(ids)) from None
    except _Stopped as stop:
        bar.close()
        raise UserError(f"{stop}. The batch stopped with {len(set(ids) & store.done_ids())} of {len(ids)} episodes "
                        f"stored in {store.out}; put that right and run the same command again: it resumes "
                        f"without redoing them") from None
    bar.close()
    if failures:
        raise EpisodeFailed(failures, len(set(ids) & store.done_ids()), len(ids), store.out / LOG_NAME)
    return store.rows(ids), len(todo)


class _Stopped(Exception):
    """An episode met what stops every episode of the batch alike (its message says what)."""


def run_sweep(spec: SweepSpec, spec_text: str, out: str | Path, backend: str = "local", workers: int = 2,
              address: str | None = None, progress: bool = True) -> dict:
    """Runs (or resumes) ``spec`` into ``out`` and writes its report; returns ``{n, done, reused, wall_s, scr}``."""
    t0 = time.perf_counter()
    check_backend(backend, workers, address)
    episodes = spec.episodes()
    store = ResultStore(out)
    store.prepare(spec_text, spec.spec_hash)
    frame, ran = run_episodes(episodes, store, backend, workers, address, log_steps=spec.log_steps,
                              progress=progress, desc=f"sweep {spec.name}")
    frame = frame.sort_values("trial_id", ignore_index=True)
    write_report(frame, Path(out), f"{spec.name} ({spec.sensor_profile} sensors, {spec.sign_geometry} signs, "
                                   f"{spec.detector} detector)")
    return {"n": len(episodes), "done": ran, "reused": len(episodes) - ran, "wall_s": time.perf_counter() - t0,
            "scr": {k: v["scr"] for k, v in summarize_settings(frame).items() if "scr" in v}}
