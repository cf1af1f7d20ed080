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
import os
from concurrent.futures import as_completed
from pathlib import Path

import pandas as pd

from experiments.episode import TABLE_SETTINGS, TrialSpec, parse_setting, run_trial
from experiments.episode.scoring import FAILURES
from experiments.stats import wilson_interval
from experiments.workers import spawn_pool

__all__ = ["SIGNS", "SPEEDS_MPS", "batch_specs", "run_batch", "run_table", "summarize"]

SIGNS = (0, 1, 2, 3)
SPEEDS_MPS = (1.0, 1.5, 2.0)


def batch_specs(setting: str, n: int, seed: int = 0, signs: tuple[int, ...] = SIGNS,
                speeds: tuple[float, ...] = SPEEDS_MPS, **params) -> list[TrialSpec]:
    """``n`` trials cycling through every (sign, speed) pair; ``params`` are further
    ``TrialSpec`` fields (``rho``, ``t_atk``, ``delay_ms``, ...). Bad values fail here, before any trial runs."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    return [TrialSpec(setting, signs[i % len(signs)], speeds[(i // len(signs)) % len(speeds)], seed + i, **params)
            for i in range(n)]


def _run_and_save(spec: TrialSpec, out_dir: str, rerun: bool = False) -> dict:
    recorder = None
    if rerun:
        from experiments.viz.rerun_log import FrameRecorder

        recorder = FrameRecorder()
    result, log = run_trial(spec, on_step=recorder)
    folder = Path(out_dir)
    if recorder is not None:
        from experiments.viz.rerun_log import write_rrd

        write_rrd(folder / f"{spec.trial_id}.rrd", log, recorder, title=f"racf trial {spec.trial_id}")
    # Log first, result last: a result file marks a finished trial.
    log.to_parquet(folder / f"{spec.trial_id}.parquet", index=False)
    tmp = folder / f"{spec.trial_id}.json.tmp"
    tmp.write_text(json.dumps(result.to_dict(), allow_nan=False))
    os.replace(tmp, folder / f"{spec.trial_id}.json")
    return result.to_dict()


def run_batch(specs: list[TrialSpec], out_dir: Path, workers: int = 2, progress: bool = True,
              rerun: bool = False) -> pd.DataFrame:
    """Runs (or resumes) the trials; returns one result row per spec, in spec order.

    With ``rerun`` each trial that runs is also recorded to ``<trial_id>.rrd`` beside its log
    (trials reused from an earlier run are not recorded again).
    """
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
            done[spec.trial_id] = _run_and_save(spec, str(folder), rerun)
            bar.update()
    elif todo:
        with spawn_pool(workers) as pool:
            futures = [pool.submit(_run_and_save, spec, str(folder), rerun) for spec in todo]
            for future in as_completed(futures):
                row = future.result()
                done[row["trial_id"]] = row
                bar.update()
    bar.close()
    results = pd.DataFrame([done[s.trial_id] for s in specs])
    results.to_parquet(Path(out_dir) / "results.parquet", index=False)
    return results


def summarize(results: pd.DataFrame, attack: bool | None = None) -> dict:
    """The protocol's summary (strict JSON: None, never NaN).

    N; SCR with its 95 % Wilson interval; ASR (attack settings); the trigger delay and the
    paper's dt_brake, mean and std over successful stops with their count; the failures by
    cause; lost-detection frames and the share of trials the attack reached.
    """
    n = int(len(results))
    k = int(results["success"].sum()) if n else 0
    if attack is None:
        attack = bool(n) and "patch" in parse_setting(str(results["setting"].iloc[0]))[0]
    scr = k / n if n else None
    ok = results[results["success"]] if n else results
    summary = {"n": n, "scr": scr, "scr_ci": list(wilson_interval(k, n)), "asr": (1.0 - scr) if attack and n else None}
    for name, col in (("trigger_delay", "trigger_delay_s"), ("dt_brake", "dt_brake_s")):
        values = pd.to_numeric(ok[col], errors="coerce").dropna() if n else pd.Series(dtype=float)
        summary[f"{name}_mean"] = float(values.mean()) if len(values) else None
        summary[f"{name}_std"] = float(values.std(ddof=1)) if len(values) > 1 else None
        if name == "dt_brake":
            summary["n_latency"] = int(len(values))
    summary["failures"] = {f: int((results["failure"] == f).sum()) for f in FAILURES} if n else {}
    if attack:
        summary["asr_ci"] = [1.0 - summary["scr_ci"][1], 1.0 - summary["scr_ci"][0]]
        # Only an attack that starts before t* can change the outcome: on approaches where the
        # sign comes into view inside the braking distance, braking starts before the protocol
        # lets the attack begin.
        early = results[pd.to_numeric(results["attack_start_s"], errors="coerce")
                        < pd.to_numeric(results["t_star_s"], errors="coerce")] if n else results
        k_early = int(early["success"].sum())
        summary["n_attack_before_t_star"] = int(len(early))
        summary["scr_attack_before_t_star"] = k_early / len(early) if len(early) else None
        summary["scr_attack_before_t_star_ci"] = list(wilson_interval(k_early, len(early)))
        summary["lost_frames_mean"] = float(results["lost_frames"].mean()) if n else None
        summary["attacked_share"] = float(results["attack_start_s"].notna().mean()) if n else None
    return summary


def run_table(n: int, out_dir: Path, seed: int = 0, settings: tuple[str, ...] = TABLE_SETTINGS, workers: int = 2,
              progress: bool = True, rerun: bool = False, **params) -> dict[str, dict]:
    """The paper's closed-loop table: ``n`` trials per setting (the same signs, speeds and
    seeds in each), one summary per setting. All specs are built, and so checked, first."""
    specs = {s: batch_specs(s, n, seed, **params) for s in settings}
    table = {}
    for setting, batch in specs.items():
        table[setting] = summarize(run_batch(batch, Path(out_dir) / setting, workers=workers, progress=progress,
                                             rerun=rerun))
    return table
