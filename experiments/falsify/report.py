"""What a set of searches found, per sampler over its seeds: the falsification rate at the budget
(Wilson interval), the median number of episodes to the first violation (with a bootstrap
interval over the seeds that found one), the lowest robustness, and the convergence plot: the
best robustness so far against episodes, the median over seeds with its quartiles.

A seed that found no violation counts as "more than the budget": the median is then reported
only if at least half the seeds found one (else None: it lies beyond the budget)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from racf.stats import median_ci, wilson_interval

__all__ = ["first_violation", "sampler_summary", "summarize_searches", "plot_convergence", "best_so_far",
           "violations_by_value"]


def first_violation(values: list[float]) -> int | None:
    """The 1-based episode count at the first violation (robustness < 0), None if none."""
    for i, v in enumerate(values, 1):
        if v < 0:
            return i
    return None


def best_so_far(values: list[float], budget: int) -> np.ndarray:
    """The lowest robustness after each of the first ``budget`` episodes (NaN before the first)."""
    out = np.full(budget, np.nan)
    if values:
        run = np.minimum.accumulate(np.asarray(values[:budget], float))
        out[: len(run)] = run
        out[len(run):] = run[-1]
    return out


def sampler_summary(per_seed: dict[int, list[float]], budget: int) -> dict:
    """One sampler's searches (seed -> robustness of each episode in order), summarised."""
    seeds = sorted(per_seed)
    firsts = {s: first_violation(per_seed[s][:budget]) for s in seeds}
    found = [f for f in firsts.values() if f is not None]
    n = len(seeds)
    lowest = {s: (min(per_seed[s][:budget]) if per_seed[s] else None) for s in seeds}
    # The median of episodes-to-first-violation, a seed with none counting as beyond the budget.
    ranked = sorted(f if f is not None else math.inf for f in firsts.values())
    median = float(np.median(ranked)) if ranked and len(found) * 2 >= n else None
    _, ci = median_ci(found)
    lows = [v for v in lowest.values() if v is not None]
    return {"n_seeds": n, "budget": budget, "falsified": len(found), "falsification_rate": len(found) / n if n else None,
            "falsification_rate_ci": list(wilson_interval(len(found), n)),
            "episodes_to_first_median": median if median is None or math.isfinite(median) else None,
            "episodes_to_first_ci_found": ci, "episodes_to_first": {str(s): firsts[s] for s in seeds},
            "lowest_robustness_m": min(lows) if lows else None,
            "lowest_robustness_median_m": float(np.median(lows)) if lows else None,
            "lowest_per_seed": {str(s): lowest[s] for s in seeds}}


def violations_by_value(trials: dict[tuple[str, int], list[tuple[int, dict, float]]], choices: dict[str, list],
                        sampler: str = "random") -> dict[str, dict[str, dict]]:
    """Where in the space the violations lie: for each choice dimension (the sign, an attack's effect,
    ...), per value, the draws of ``sampler`` (random search's draws map the space without a bias),
    their violations and the share with its Wilson interval. Empty when that sampler did not run.

    ``trials``: (sampler, seed) -> (number, params, robustness) told; ``choices``: dimension -> values."""
    told = [(params, value) for (name, _), rows in trials.items() if name == sampler for _, params, value in rows]
    out: dict[str, dict[str, dict]] = {}
    for dim, values in choices.items():
        per = {}
        for v in values:
            hits = [value < 0 for params, value in told if params.get(dim) == v]
            k, n = int(sum(hits)), len(hits)
            per[str(v)] = {"n": n, "violations": k, "share": k / n if n else None,
                           "share_ci": list(wilson_interval(k, n))}
        out[dim] = per
    return out if told else {}


def summarize_searches(values: dict[tuple[str, int], list[float]], budget: int) -> dict[str, dict]:
    """``{(sampler, seed): values}`` -> a summary per sampler."""
    samplers = sorted({s for s, _ in values}, key=lambda s: ("tpe", "cmaes", "random").index(s)
                      if s in ("tpe", "cmaes", "random") else 9)
    return {s: sampler_summary({seed: v for (name, seed), v in values.items() if name == s}, budget) for s in samplers}


def plot_convergence(values: dict[tuple[str, int], list[float]], budget: int, path: Path, title: str) -> Path:
    """The best robustness so far against episodes, per sampler (median over seeds, quartile band)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    x = np.arange(1, budget + 1)
    colours = {"tpe": "tab:blue", "cmaes": "tab:orange", "random": "tab:grey"}
    for sampler in sorted({s for s, _ in values}):
        curves = np.array([best_so_far(v, budget) for (s, _), v in values.items() if s == sampler])
        with np.errstate(all="ignore"):
            q1, med, q3 = np.nanpercentile(curves, [25, 50, 75], axis=0)
        colour = colours.get(sampler)
        ax.plot(x, med, label=f"{sampler} (median of {len(curves)} seeds)", color=colour)
        ax.fill_between(x, q1, q3, alpha=0.2, color=colour)
    ax.axhline(0.0, color="tab:red", lw=0.8, ls="--")
    ax.text(1, 0.0, "below: a violation", va="top", ha="left", color="tab:red", fontsize=8)
    ax.set(xlabel="episodes", ylabel="lowest robustness so far (m)", title=title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
