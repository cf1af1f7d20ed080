"""``racf trials`` batches and the paper's closed-loop table, on the one batch path.

Trial i of a batch drives sign ``SIGNS[i % 4]`` at speed ``SPEEDS_MPS[(i // 4) % 3]`` with
seed ``seed + i``, so any 12 consecutive trials cover every sign at every speed. A batch
keeps every trial's per-step log: ``<out>/trials/<trial_id>.parquet`` beside the store's
``<out>/parts/``, and ``<out>/results.parquet`` with the rows in trial order. A rerun reuses
every stored trial (a longer batch reuses the shorter one's trials).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from racf.experiments.episode import TABLE_SETTINGS, TrialSpec, parse_setting
from racf.experiments.sweeps.executors import backend_session
from racf.experiments.sweeps.run import run_episodes
from racf.provenance import atomic_write
from racf.experiments.sweeps.store import ResultStore
from racf.experiments.sweeps.summary import summarize

__all__ = ["SIGNS", "SPEEDS_MPS", "TRIALS_LOGS", "batch_specs", "run_batch", "run_table", "PHYSICAL_TABLE_ROWS",
           "TABLES"]

SIGNS = (0, 1, 2, 3)
SPEEDS_MPS = (1.0, 1.5, 2.0)
#: The folder of a batch's per-step logs and recordings.
TRIALS_LOGS = "trials"


def batch_specs(setting: str, n: int, seed: int = 0, signs: tuple[int, ...] = SIGNS,
                speeds: tuple[float, ...] = SPEEDS_MPS, estimator_options: dict[str, dict] | None = None,
                **params) -> list[TrialSpec]:
    """``n`` trials cycling through every (sign, speed) pair; ``params`` are further
    ``TrialSpec`` fields (``rho``, ``t_atk``, ``delay_ms``, ...), ``estimator_options`` the options
    by estimator name (each trial takes its own estimator's). Bad values fail here, before any trial runs."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    options = (estimator_options or {}).get(parse_setting(setting)[1], {})
    return [TrialSpec(setting, signs[i % len(signs)], speeds[(i // len(signs)) % len(speeds)], seed + i,
                      estimator_options=options, **params)
            for i in range(n)]


def run_batch(specs: list[TrialSpec], out_dir: Path, workers: int = 2, progress: bool = True, rerun: bool = False,
              backend: str = "local", address: str | None = None, log_steps: bool = True,
              desc: str = "trials") -> pd.DataFrame:
    """Runs (or resumes) the trials; returns one result row per spec, in spec order.

    With ``rerun`` each trial that runs is also recorded to ``trials/<trial_id>.rrd``;
    ``log_steps=False`` keeps no per-step logs (the rows are the same).
    """
    store = ResultStore(out_dir, TRIALS_LOGS)
    results, _ = run_episodes(specs, store, backend, workers, address, log_steps=log_steps, rerun=rerun,
                              progress=progress, desc=desc)
    atomic_write(Path(out_dir) / "results.parquet", results)
    return results


_FROM_START = {"attack_params": {"physical_patch": {"from_start": True}}}
#: The table with the sticker printed on the sign (``physical_patch``, on the protocol's schedule and
#: from the episode's start), by row label: (setting, further ``TrialSpec`` fields).
PHYSICAL_TABLE_ROWS: dict[str, tuple[str, dict]] = {
    "clean": ("clean", {}),
    "physical_patch": ("clean+physical_patch", {}),
    "physical_patch+odca": ("clean+physical_patch+odca", {}),
    "physical_patch+ekf": ("clean+physical_patch+ekf", {}),
    "physical_patch from start": ("clean+physical_patch", _FROM_START),
    "physical_patch+odca from start": ("clean+physical_patch+odca", _FROM_START),
    "physical_patch+ekf from start": ("clean+physical_patch+ekf", _FROM_START),
}
#: The closed-loop tables ``racf trials --table --patch`` runs: the occluder's (the paper's table)
#: and the printed sticker's.
TABLES: dict[str, dict[str, tuple[str, dict]]] = {
    "occlusion": {s: (s, {}) for s in TABLE_SETTINGS},
    "physical": PHYSICAL_TABLE_ROWS,
}


def run_table(n: int, out_dir: Path, seed: int = 0, settings: tuple[str, ...] = TABLE_SETTINGS, workers: int = 2,
              progress: bool = True, rerun: bool = False, backend: str = "local", address: str | None = None,
              rows: dict[str, tuple[str, dict]] | None = None, **params) -> dict[str, dict]:
    """A closed-loop table: ``n`` trials per row (the same signs, speeds and seeds in each), one
    summary per row. The rows are ``settings`` (the paper's table by default) or, given, ``rows``
    (label -> (setting, further spec fields)). All specs are built, and so checked, first."""
    rows = rows if rows is not None else {s: (s, {}) for s in settings}
    specs = {label: batch_specs(setting, n, seed, **{**params, **extra}) for label, (setting, extra) in rows.items()}
    with backend_session(backend, workers, address):
        return {label: summarize(run_batch(batch, Path(out_dir) / label.replace(" ", "_"), workers=workers,
                                           progress=progress, rerun=rerun, backend=backend, address=address,
                                           desc=label))
                for label, batch in specs.items()}


#: The paper's closed-loop numbers (its Table 4, QCar 2), printed beside ours for comparison.
PAPER_TABLE = {"platform": "QCar 2", "n": 30, "rows": {
    "clean": {"scr": 1.00, "dt_brake_s": 0.165},
    "attack": {"scr": 0.17, "dt_brake_s": 2.65},
    "attack+odca": {"scr": 0.80, "dt_brake_s": 0.190}}}
