"""Batches of closed-loop trials: specs, parallel runs that resume, and the summary.

Trial i of a batch drives sign ``SIGNS[i % 4]`` at speed ``SPEEDS[(i // 4) % 3]`` with
seed ``seed + i``, so any 12 consecutive trials cover every sign at every speed. Each
finished trial leaves ``<out>/trials/<trial_id>.json`` (result row) and ``.parquet``
(per-step log); a rerun skips trials whose files exist, so an interrupted batch resumes
without redoing finished work. Workers are spawned, never forked (see the README: a
process that has made a GL context must not fork renderers).
"""

from __future__ import annotations

import json
import math
import multiprocessing as mp
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
import pandas as pd

from experiments.stats import wilson_interval
from experiments.trial import TrialSpec, run_trial

__all__ = ["SIGNS", "SPEEDS_MPS", "batch_specs", "run_batch", "summarize"]

SIGNS = (0, 1, 2, 3)
SPEEDS_MPS = (1.0, 1.5, 2.0)


def batch_specs(setting: str, n: int, seed: int = 0, signs: tuple[int, ...] = SIGNS,
                speeds: tuple[float, ...] = SPEEDS_MPS, **attack) -> list[TrialSpec]:
    """``n`` trials cycling through every (sign, speed) pair; ``attack`` holds ``rho`` / ``t_atk``."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    return [TrialSpec(setting, signs[i % len(signs)], speeds[(i // len(signs)) % len(speeds)], seed + i, **attack)
            for i in range(n)]


def _run_and_save(spec: TrialSpec, out_dir: str) -> dict:
    result, log = run_trial(spec)
    folder = Path(out_dir)
    # Log first, result last: a result file marks a finished trial.
    log.to_parquet(folder / f"{spec.trial_id}.parquet", index=False)
    tmp = folder / f"{spec.trial_id}.json.tmp"
    tmp.write_text(json.dumps(result.to_dict()))
    os.replace(tmp, folder / f"{spec.trial_id}.json")
    return result.to_dict()


def run_batch(specs: list[TrialSpec], out_dir: Path, workers: int = 2, progress: bool = True) -> pd.DataFrame:
    """Runs (or resumes) the trials; returns one result row per spec, in spec order."""
    from tqdm import tqdm

    folder = Path(out_dir) / "trials"
    folder.mkdir(parents=True, exist_ok=True)
    done: dict[str, dict] = {}
    for spec in specs:
        path = folder / f"{spec.trial_id}.json"
        if path.exists():
            done[spec.trial_id] = json.loads(path.read_text())
    todo = [s for s in specs if s.trial_id not in done]
    bar = tqdm(total=len(specs), initial=len(specs) - len(todo), desc="trials", unit="trial", disable=not progress)
    if workers <= 1:
        for spec in todo:
            done[spec.trial_id] = _run_and_save(spec, str(folder))
            bar.update()
    elif todo:
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as pool:
            futures = [pool.submit(_run_and_save, spec, str(folder)) for spec in todo]
            for future in as_completed(futures):
                row = future.result()
                done[row["trial_id"]] = row
                bar.update()
    bar.close()
    results = pd.DataFrame([done[s.trial_id] for s in specs])
    results.to_parquet(Path(out_dir) / "results.parquet", index=False)
    return results


def summarize(results: pd.DataFrame, attack: bool = False) -> dict:
    """The protocol's summary: N, SCR with its 95 % Wilson interval, ASR, latency over successes."""
    n = int(len(results))
    k = int(results["success"].sum())
    scr = k / n if n else math.nan
    latencies = results.loc[results["success"], "latency_s"].astype(float)
    latencies = latencies[np.isfinite(latencies)]
    summary = {
        "n": n,
        "scr": scr,
        "scr_ci": list(wilson_interval(k, n)),
        "asr": (1.0 - scr) if attack else None,
        "latency_mean": float(latencies.mean()) if len(latencies) else None,
        "latency_std": float(latencies.std(ddof=1)) if len(latencies) > 1 else None,
        "n_latency": int(len(latencies)),
    }
    if attack:
        summary["asr_ci"] = [1.0 - summary["scr_ci"][1], 1.0 - summary["scr_ci"][0]]
        summary["lost_frames_mean"] = float(results["lost_frames"].mean()) if n else None
        summary["attacked_share"] = float(results["attack_start_s"].notna().mean()) if n else None
    return summary

