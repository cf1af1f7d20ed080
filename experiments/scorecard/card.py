"""One defence's card on a battery: every row run (or reused) and summarised.

Episodes are ordinary episodes with ids, stored under ``out/episodes/`` and shared by every
card made in ``out`` (an episode two rows or two batteries hold runs once): a rerun, or a run after a SIGKILL, reuses what is stored and runs
only what is missing. The offline rows are cached under ``out/offline/`` by the defence's
code version (its plug-in source included), the dataset's hash and the battery, so they are
computed once per version. Wall times and per-step times sit under ``timing``, the only part
of the card that differs between two runs of the same command.
"""

from __future__ import annotations

import hashlib
import json
import time
from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path

import pandas as pd

from racf.experiments.episode import TrialSpec
from racf.experiments.scorecard.battery import PENALTIES, Battery
from racf.experiments.scorecard.detection import detection_rows
from racf.experiments.scorecard.drives import bootstrap_mean, driving_rows
from racf.experiments.scorecard.link import link_services
from racf.experiments.scorecard.proof import card_episodes
from racf.provenance import atomic_write, commit
from racf.sim.world.manager import world_targets
from racf.experiments.sweeps.store import ResultStore
from racf.experiments.metrics.criteria import card_measures
from racf.experiments.sweeps.summary import plugin_measures, stealth_summary, summarize

__all__ = ["run_card", "row_summary", "card_version", "racf_commit"]


def racf_commit() -> str:
    """The commit of the racf checkout the card runs (``+changes`` if its code differs from it; not a
    checkout, for an installed wheel): what ``racf board check`` asks of a card for the board."""
    import racf

    return commit(Path(racf.__file__).resolve().parents[1])


def card_version(defence: str) -> str:
    """The code a card depends on: racf's episode code and, for a plug-in, its own source (as a
    trial id holds it)."""
    import racf

    digest = TrialSpec("clean" + ("" if defence == "raw" else f"+{defence}"), 0, 1.0, 0).trial_id.rsplit("_", 1)[1]
    return f"racf {racf.__version__}, code {digest}"


def _loop_summary(rows: pd.DataFrame, attacked: bool) -> dict:
    s = summarize(rows, attack=attacked)
    keep = ("n", "scr", "scr_ci", "asr", "asr_ci", "n_attack_before_t_star", "scr_attack_before_t_star",
            "scr_attack_before_t_star_ci", "dt_brake_mean", "dt_brake_std", "n_latency", "failures",
            "robustness_median_m", "robustness_ci", "robustness_p5_m", "robustness_min_m", "violation_share",
            "violation_share_ci", "n_traffic", "collision_rate", "collision_rate_ci", "conflicts",
            "n_traffic_attack_before_t_star", "collision_rate_attack_before_t_star",
            "collision_rate_attack_before_t_star_ci")
    summary = {k: s.get(k) for k in keep if k in s} | {"measures": plugin_measures(rows, attacked)}
    if "driving_score" in rows and rows["driving_score"].notna().any():  # the criteria's penalties, per episode
        scores = rows["driving_score"].dropna().to_numpy(float)
        summary |= {"driving_score": float(scores.mean()), "driving_score_ci": bootstrap_mean(scores)}
    declared = card_measures(rows)  # what the rows' criteria put on a card (collision-free, say)
    if declared:
        summary["headline"] = declared
    if "sign_stands" in rows and not rows["sign_stands"].fillna(True).astype(bool).any():
        # No sign stood (a removed sign, a phantom): stopping is the failure, measured as needless stops.
        summary |= {"scr": None, "scr_ci": [None, None], "n_needless": int(len(rows))}
    return summary



#: The offline reference every card's strong RMSE is divided by.
REFERENCE = "chronos"


def _cached_offline(defence: str, options: dict | None, dataset, battery: Battery, draws: int, out: Path) -> dict:
    """A defence's offline rows, computed once per code version, options, dataset and battery."""
    from racf.experiments.scorecard.offline import offline_rows

    key = hashlib.sha256(json.dumps([card_version(defence), options or {}, _dataset_hash(dataset), battery.name,
                                     draws], sort_keys=True).encode()).hexdigest()[:16]
    cache = out / "offline" / f"{defence}-{key}.json"
    if cache.exists():
        return json.loads(cache.read_text())
    rows = {**offline_rows(defence, dataset, battery.offline_presets, draws, options), "split": battery.offline_split}
    cache.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(cache, json.dumps(rows, allow_nan=False))
    return rows


def _dataset_hash(ds) -> str:
    """The test drives the offline rows read, so a new dataset is a new cache key."""
    from racf.experiments.offline.benchmark import frame_hash

    return frame_hash(ds.clean("test"))


def row_summary(frame: pd.DataFrame, attacked: bool) -> dict:
    """What a row's result rows say on its card (the driving score aside, which reads the step logs):
    ``racf board verify`` sums a card's carried episodes up again with it."""
    summary = _loop_summary(frame, attacked)
    return summary | _stealth(frame) if attacked else summary


def _stealth(frame: pd.DataFrame) -> dict:
    """The row's undetected error (``scoring.stealth``), and per attack rate where the row varies it."""
    keep = ("undetected_error_median", "undetected_error_ci", "detected_share", "detected_share_ci")
    out = {k: v for k, v in stealth_summary(frame).items() if k in keep}
    if "param_rate_mps" in frame and frame["param_rate_mps"].notna().any():
        out["by_rate"] = {f"{rate:g}": {k: v for k, v in stealth_summary(rows).items() if k in keep}
                          for rate, rows in frame.groupby("param_rate_mps", sort=True)}
    return out


def _logs(store: ResultStore, ids: list[str]) -> list[pd.DataFrame]:
    return [pd.read_parquet(store.log_path(i)) for i in ids]


def run_card(defence: str, battery: Battery, out: Path, *, quick: bool = False, dataset=None,
             backend: str = "local", workers: int = 2, address: str | None = None, progress: bool = True,
             options: dict | None = None, service: dict | None = None) -> dict:
    """Runs (or resumes) ``battery`` for ``defence`` and returns its card (strict-JSON-ready).
    ``service``: the spec fields that run the defence in a ``racf serve`` process (``estimator_endpoint``).

    ``dataset`` is the offline rows' ``QCarDataset`` (by-series split); None leaves them out.
    """
    from racf.experiments.scorecard.offline import step_times_ms, trainable_parameters
    from racf.experiments.sweeps.run import run_episodes

    t0 = time.perf_counter()
    out = Path(out)
    card: dict = {"battery": battery.name + ("-quick" if quick else ""), "quick": quick, "defence": defence,
                  "version": card_version(defence), "commit": racf_commit(), "options": dict(options or {}),
                  "sensor_profile": "qcar2", "closed_loop": {}, "drives": {}, "episodes": {}}
    timing: dict = {}
    links = {row.link for row in battery.rows() if row.link}
    with link_services(defence, options, links, out) if links else nullcontext({}) as served:
        plan = []
        for row in battery.rows():
            specs = row.specs(defence, quick)
            if options:
                specs = [replace(s, estimator_options=options) for s in specs]
            if row.link:  # the battery's own service for this row's link
                specs = [replace(s, **served[row.link]) for s in specs]
            elif service:
                specs = [replace(s, **service) for s in specs]
            plan.append((row, specs))
        # One batch for the whole card: one pool of workers, each keeping its env and models from
        # episode to episode, and the long drives first so that no worker idles at the end.
        unique = {s.trial_id: s for _, specs in sorted(plan, key=lambda p: p[0] not in battery.drives) for s in specs}
        store = ResultStore(out / "episodes")
        t_run = time.perf_counter()
        _, ran = run_episodes(list(unique.values()), store, backend, workers, address, log_steps=True,
                              progress=progress, desc=f"{defence}: episodes")
    timing.update(episodes_s=time.perf_counter() - t_run, episodes=len(unique), episodes_run=ran)
    loop_logs: list[pd.DataFrame] = []
    for row, specs in plan:
        ids = [s.trial_id for s in specs]
        frame, logs = store.rows(ids), _logs(store, ids)
        summary = {"title": row.title, "detector": specs[0].detector, **row_summary(frame, row.attacked)}
        card["episodes"][row.key] = card_episodes(frame, logs)
        scored = row in battery.drives or row.driving  # only a drive's score reads the declared vehicles
        vehicles = {t.name for s in specs for t in world_targets(s.scenario.world(s, s.scenario_params), "vehicle")
                    } if scored else set()
        if row in battery.drives:
            card["drives"][row.key] = {**summary, **driving_rows(frame, logs, PENALTIES, vehicles)}
        elif row.driving:  # a closed-loop row scored as drives too (other cars: the vehicle-hit penalty)
            card["closed_loop"][row.key] = {**summary, **driving_rows(frame, logs, PENALTIES, vehicles)}
            loop_logs += logs
        else:
            card["closed_loop"][row.key] = summary
            loop_logs += logs
    card["detection"] = detection_rows(loop_logs)
    card["penalties"] = PENALTIES
    card["cost"] = {"parameters": trainable_parameters(defence, options)}
    if dataset is not None and battery.offline_presets:
        t_off = time.perf_counter()
        draws = battery.offline_draws_quick if quick else battery.offline_draws
        card["offline"] = _cached_offline(defence, options, dataset, battery, draws, out)
        reference = _cached_offline(REFERENCE, None, dataset, battery, draws, out)
        strong, ref = card["offline"].get("strong", {}), reference.get("strong", {})
        if strong.get("rmse") is not None and ref.get("rmse"):
            card["offline"]["strong_ratio_to_chronos"] = strong["rmse"] / ref["rmse"]
        timing["offline_s"] = time.perf_counter() - t_off
        timing["step_time"] = step_times_ms(defence, dataset, options)
    timing["wall_s"] = time.perf_counter() - t0
    card["timing"] = timing
    return card
