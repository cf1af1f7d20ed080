"""``racf falsify`` end to end: the searches, the report (JSON, table, convergence plot) and the
distinct violations recorded as cases (spec + rerun recording), in one results folder:

    out/episodes/      every evaluated episode (a sweep's store: reused by id)
    out/studies/       one Optuna journal per search (resumed after a kill)
    out/report.json    the report (strict JSON)
    out/convergence.png
    out/worst.png      the worst case found: the camera as the attack struck, and the trace
    out/cases/         a case file and its .rrd recording per distinct violation
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

from racf.errors import Interrupted
from racf.experiments.falsify.cases import distinct, save_case
from racf.experiments.falsify.pool import EpisodePool
from racf.experiments.falsify.report import plot_convergence, summarize_searches, violations_by_value
from racf.experiments.falsify.search import SearchConfig, episode_seed, objective_value, run_searches
from racf.experiments.episode.preflight import check_specs
from racf.experiments.falsify.space import load_space
from racf.provenance import atomic_write
from racf.experiments.sweeps.store import ResultStore

__all__ = ["falsify", "render"]


def falsify(defence: str, attacks: tuple[str, ...], out: str | Path, budget: int = 100,
            samplers: tuple[str, ...] = ("tpe", "cmaes", "random"), seeds: tuple[int, ...] = tuple(range(10)),
            batch: int = 4, space_path: str | Path | None = None, fixed: dict | None = None,
            stop_at_violation: bool = False, backend: str = "local", workers: int = 2, address: str | None = None,
            cases: bool = True, progress: bool = True, objective: str = "rule") -> dict:
    """Runs (or resumes) the searches and writes the report; returns it."""
    t0 = time.perf_counter()
    out = Path(out)
    space = load_space(defence, attacks, space_path, fixed)
    check_specs(space.extremes())  # a bound out of range is refused now: nothing drawn, nothing written
    cfg = SearchConfig(space, tuple(samplers), tuple(seeds), budget, batch, stop_at_violation, objective)
    store = ResultStore(out / "episodes")
    try:
        with EpisodePool(store, backend, workers, address) as pool:
            searches = run_searches(cfg, out, pool, progress)
            ran = pool.ran
    except Interrupted:  # a round's counts say little of a search: count what the whole search has stored
        raise Interrupted(len(store.done_ids()), None) from None
    trials = {key: search.trials() for key, search in searches.items()}  # (number, params, robustness)
    values = {key: [value for *_, value in told] for key, told in trials.items()}
    violations = [(sampler, seed, number, params, value) for (sampler, seed), told in trials.items()
                  for number, params, value in told if value < 0]
    report = {"defence": defence, "attacks": list(attacks), "setting": space.setting, "space": space.to_json(),
              "budget": budget, "batch": batch, "seeds": list(seeds), "stop_at_violation": stop_at_violation,
              "objective": objective,
              "samplers": summarize_searches(values, budget), "episodes_run": ran,
              "episodes_evaluated": sum(len(v) for v in values.values())}
    plot_convergence(values, budget, out / "convergence.png", f"{space.setting}: {len(seeds)} seeds per sampler")
    report["convergence_png"] = "convergence.png"
    report["cases"] = (_record_cases(space, violations, store, out / "cases", backend, workers, address, objective)
                       if cases else [])
    report["violations_by_value"] = violations_by_value(
        trials, {d.name: list(d.choices) for d in space.dimensions if d.choices is not None})
    report["worst"] = _worst(space, trials)
    if report["worst"] is not None:
        from racf.experiments.falsify.figure import worst_case_figure

        worst = report["worst"]
        spec = space.trial_spec(worst["params"], episode_seed(worst["seed"], worst["trial"]))
        worst_case_figure(spec, out / "worst.png", f"{space.setting}: the lowest robustness of {len(seeds)} x "
                                                   f"{len(samplers)} searches")
        report["worst_png"] = "worst.png"
    report["wall_s"] = time.perf_counter() - t0
    atomic_write(out / "report.json", json.dumps(report, indent=1, allow_nan=False))
    return report


def _worst(space, trials: dict) -> dict | None:
    """The lowest-robustness episode over every search: its parameters and result."""
    told = [(key, number, params, value) for key, rows in trials.items() for number, params, value in rows]
    if not told:
        return None
    (sampler, seed), number, params, value = min(told, key=lambda t: t[3])
    spec = space.trial_spec(params, episode_seed(seed, number))
    return {"sampler": sampler, "seed": seed, "trial": number, "params": params, "robustness_m": value,
            "trial_id": spec.trial_id}


def _record_cases(space, violations: list, store: ResultStore, folder: Path, backend: str, workers: int,
                  address: str | None, objective: str = "rule") -> list[dict]:
    """The distinct violations, each run again with a rerun recording into ``folder`` and saved as a case."""
    if not violations:
        return []
    specs = [space.trial_spec(params, episode_seed(seed, number)) for _, seed, number, params, _ in violations]
    found = store.rows([spec.trial_id for spec in specs])
    # A scenario with no stop rule (the car ahead) names no failure: its violation is its objective's.
    failures = found["failure"].tolist() if "failure" in found else [objective] * len(specs)
    rows = [{"setting": spec.setting, "sign": spec.sign, "robustness_m": value, "spec": spec, "failure": failure,
             "found_by": {"sampler": sampler, "seed": seed, "trial": number}}
            for spec, failure, (sampler, seed, number, _, value) in zip(specs, failures, violations)]
    keep = distinct(rows)
    recordings = ResultStore(folder, logs_dir=".")
    with EpisodePool(recordings, backend, workers, address, rerun=True) as pool:
        replayed = pool.run([r["spec"] for r in keep])
    saved = []
    for row, (_, result) in zip(keep, replayed.iterrows()):
        value = objective_value(result.to_dict(), objective)
        failure = result.get("failure", row["failure"])
        path = save_case(folder, row["spec"], {**result.to_dict(), "robustness_m": value, "failure": failure},
                         row["found_by"])
        saved.append({"case": path.name, "recording": f"{row['spec'].trial_id}.rrd", "robustness_m": value,
                      "failure": failure, "sign": row["sign"],
                      "replayed_identical": bool(value == row["robustness_m"])})
    return saved


def render(report: dict) -> str:
    """The report as the table ``racf falsify`` prints."""
    lines = [f"racf falsify: {report['setting']}, objective {report.get('objective', 'rule')}, "
             f"budget {report['budget']} episodes per search, "
             f"{len(report['seeds'])} seeds per sampler ({report['episodes_run']} episodes run now, "
             f"{report['episodes_evaluated']} evaluated, {report['wall_s']:.0f} s)", "",
             "| sampler | falsified (rate, 95 % CI) | median episodes to first violation | lowest robustness m |",
             "|---|---|---|---|"]
    for name, s in report["samplers"].items():
        median = s["episodes_to_first_median"]
        median = f"{median:g}" if median is not None else f"> {s['budget']} (under half the seeds)"
        lo, hi = s["falsification_rate_ci"]
        lowest = s["lowest_robustness_m"]
        lines.append(f"| {name} | {s['falsified']}/{s['n_seeds']} = {s['falsification_rate']:.2f} [{lo:.2f}, {hi:.2f}] "
                     f"| {median} | {lowest:+.3f} |" if lowest is not None and math.isfinite(lowest) else
                     f"| {name} | {s['falsified']}/{s['n_seeds']} | {median} | - |")
    worst = report.get("worst")
    if worst:
        lines += ["", f"worst case: robustness {worst['robustness_m']:+.3f} m ({worst['sampler']}, seed {worst['seed']}, "
                      f"trial {worst['trial']}): " + ", ".join(f"{k}={_fmt(v)}" for k, v in worst["params"].items())]
    if report["cases"]:
        lines += ["", f"{len(report['cases'])} distinct violation(s) recorded as cases (racf replay-case FILE):"]
        lines += [f"  cases/{c['case']}  robustness {c['robustness_m']:+.3f} m, {c['failure']}, "
                  f"replayed {'to the bit' if c['replayed_identical'] else 'DIFFERENTLY'}" for c in report["cases"]]
    lines += ["", "convergence plot: convergence.png; the worst case's picture and trace: worst.png (results folder)"]
    return "\n".join(lines)


def _fmt(value) -> str:
    return f"{value:.3g}" if isinstance(value, float) else str(value)
