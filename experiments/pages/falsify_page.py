"""The falsification results page (``docs/results/falsification.md``), from the stored reports of
``racf falsify`` (``falsify-*`` in ``docs/results/data``) and their figures in ``docs/falsify/``."""

from __future__ import annotations

import json
from pathlib import Path

from racf.experiments.episode.robustness import STOP_RULE
from racf.experiments.pages.results_format import meta_lines, page_head

__all__ = ["falsification_markdown", "FALSIFY_RESULTS", "RESEED_RESULT", "guided_verdict"]

#: The stored searches the page shows: (result name, what it is, the command).
FALSIFY_RESULTS = (
    ("falsify-odca-dropout", "ODCA under the timed dropout",
     "racf falsify --defence odca --attack dropout_timed --budget 100 --seeds 10"),
    ("falsify-odca-dropout-frustum", "ODCA under the timed dropout and the frustum spoof together (the space "
     "with dropout_timed, widened by the white-box spoof, which may also draw the sign smaller)",
     "racf falsify --defence odca --attack dropout_timed,frustum_spoof --budget 100 --seeds 10"),
    ("falsify-odca-dropout-undetected", "ODCA under the timed dropout, the samplers steered by the undetected error",
     "racf falsify --defence odca --attack dropout_timed --budget 100 --seeds 10 --objective rule-undetected"),
    ("falsify-raw-strong-patch", "Raw depth under the paper's strong patch (the sanity check)",
     "racf falsify --defence raw --attack patch_occlusion --space experiments/falsify/spaces/strong-patch.toml "
     "--budget 20 --seeds 10"),
    ("falsify-raw-patch", "Raw depth under the patch, the whole shipped space",
     "racf falsify --defence raw --attack patch_occlusion --budget 20 --seeds 10"),
)


def guided_verdict(samplers: dict) -> str:
    """Whether TPE or CMA-ES beat random search: a median at least 3 x lower, or falsifying more
    seeds with the two 95 % intervals apart (a difference inside them is not a win)."""
    rnd = samplers.get("random")
    if rnd is None:
        return "No random-search baseline was run."
    words = []
    for name in ("tpe", "cmaes"):
        s = samplers.get(name)
        if s is None:
            continue
        med, base = s["episodes_to_first_median"], rnd["episodes_to_first_median"]
        faster = med is not None and (base is None or base >= 3 * med)
        apart = s["falsification_rate_ci"][0] > rnd["falsification_rate_ci"][1]
        if faster or apart:
            verdict = "beats random search"
        elif s["falsified"] > rnd["falsified"]:
            verdict = "falsifies more seeds than random search, but inside both 95 % intervals: not a clear win"
        else:
            verdict = "does not beat random search"
        words.append(f"{_NAMES.get(name, name)} {verdict} (median episodes to the first violation {_fmt(med)} "
                     f"against {_fmt(base)}; found one in {s['falsified']}/{s['n_seeds']} seeds against "
                     f"{rnd['falsified']}/{rnd['n_seeds']})")
    return "; ".join(words) + "."


_NAMES = {"tpe": "TPE", "cmaes": "CMA-ES", "random": "random search"}


def _why(samplers: dict) -> list[str]:
    """Why guided search did not clearly beat random here, from the numbers: a flat landscape with a cliff."""
    guided = [samplers[n] for n in ("tpe", "cmaes") if n in samplers]
    rnd = samplers.get("random")
    if not guided or rnd is None or any(g["falsification_rate_ci"][0] > rnd["falsification_rate_ci"][1] or
                                        (g["episodes_to_first_median"] is not None) for g in guided):
        return []
    lows = [s["lowest_robustness_median_m"] for s in samplers.values()]
    return [f"Why: the median over seeds of each search's lowest robustness is {min(lows):+.3f} to {max(lows):+.3f} m: "
            "every sampler soon finds stops a decimetre or so before the line, but the violations are isolated "
            "points below them (a brake a little late at one sign and speed, or a track lost and the line run by "
            "a metre). Off those points the rule's robustness is the stop's gap, which says little about how near "
            "the attack came to winning, so a model of the landscape has little slope to follow, and CMA-ES draws "
            "the sign and the attack's effect at random.", ""]


def _regions(report: dict) -> list[str]:
    """Where random search's draws broke the rule, per value of each choice (an unbiased map of the space)."""
    by = report.get("violations_by_value") or {}
    if not by:
        return []
    first = next(iter(by.values()))
    k, n = sum(v["violations"] for v in first.values()), sum(v["n"] for v in first.values())
    lines = [f"**Where the violations are.** Random search's {n} draws broke the rule {k} times "
             f"({100 * k / n:.1f} %); per value of each choice (violations / draws, share [95 % CI]):", "",
             "| parameter | value | violations / draws | share [95 % CI] |", "|---|---|---|---|"]
    for dim, per in by.items():
        for value, v in per.items():
            lo, hi = v["share_ci"]
            share = "-" if v["share"] is None else f"{v['share']:.3f} [{lo:.3f}, {hi:.3f}]"
            lines.append(f"| {dim} | {value} | {v['violations']} / {v['n']} | {share} |")
    return lines + [""]


def _fmt(median) -> str:
    return "beyond the budget" if median is None else f"{median:g}"


def _table(samplers: dict) -> list[str]:
    lines = ["| sampler | seeds | falsified at the budget (95 % CI) | median episodes to first violation | "
             "lowest robustness m (median over seeds) |", "|---|---|---|---|---|"]
    for name, s in samplers.items():
        lo, hi = s["falsification_rate_ci"]
        low, med_low = s["lowest_robustness_m"], s["lowest_robustness_median_m"]
        lines.append(f"| {name} | {s['n_seeds']} | {s['falsified']}/{s['n_seeds']} = {s['falsification_rate']:.2f} "
                     f"[{lo:.2f}, {hi:.2f}] | {_fmt(s['episodes_to_first_median'])} | "
                     f"{low:+.3f} ({med_low:+.3f}) |")
    return lines + [""]


def _worst(report: dict) -> list[str]:
    worst = report.get("worst")
    if not worst:
        return []
    lines = [f"**The worst case found**: robustness {worst['robustness_m']:+.3f} m ({worst['sampler']}, search seed "
             f"{worst['seed']}, trial {worst['trial']}; episode `{worst['trial_id']}`).", "",
             "| parameter | value |", "|---|---|"]
    lines += [f"| {k} | {v:.3g} |" if isinstance(v, float) else f"| {k} | {v} |" for k, v in worst["params"].items()]
    return lines + [""]


def _cases(report: dict) -> list[str]:
    cases = report.get("cases") or []
    if not cases:
        return ["No violation was found, so no case was recorded.", ""]
    lines = [f"{len(cases)} distinct violation(s) (one per sign and failure), each replayed to the same robustness "
             "to the bit when recorded:", "", "| case | sign | failure | robustness m | replayed to the bit |",
             "|---|---|---|---|---|"]
    lines += [f"| `{c['case']}` | {c['sign']} | {c['failure']} | {c['robustness_m']:+.3f} | "
              f"{'yes' if c['replayed_identical'] else 'NO'} |" for c in cases]
    return lines + [""]


def falsification_markdown(root: Path) -> str:
    """The page from the stored results in ``root`` (``docs/results/data``)."""
    root = Path(root)
    figures = root.parent.parent / "falsify"
    lines = page_head(
        "Falsification: each defence's worst case",
        "`racf falsify` searches the attack and scenario space (the sign, the speed, the run-up, when the attack may "
        "start after first sight, and the attack's own settings) for the episodes that break the stop rule, written "
        "in signal temporal logic and scored by [rtamt](https://github.com/nickovic/rtamt):",
        f"`{STOP_RULE}` (discrete time at 50 Hz: 150 steps are 3 s)",
        "over each approach (until the car first rests): the bumper never crosses the line, and once within 0.60 m of "
        "it the car is at rest within 3 s (`rest` is 20 s x (0.05 m/s - speed), so both clauses read in metres). "
        "Robustness is signed: negative is a violation, and its size says by how much. Every episode of racf now "
        "logs it (`robustness_m`), and sweep summaries report its distribution.",
        "Each search is an Optuna study: TPE and CMA-ES (guided) and random search (the baseline), 10 search seeds "
        "each. A trial's episode seed comes from the search seed and the trial number, so every sampler meets the "
        "same noise at the same step; TPE and CMA-ES start with the same 10 random trials as random search.",
        "By default the samplers minimise the rule's robustness. With `--objective rule-undetected` they minimise it "
        "minus the attack's undetected error (the referee's largest gap between the distance the car acted on and "
        "the truth before the defence flagged the attack): a slope towards attacks the defence does not see. A "
        "violation is always the rule's robustness below zero, and the tables report the rule's robustness; random "
        "search ignores the objective, so its rows are the same episodes either way.")
    for name, what, command in FALSIFY_RESULTS:
        lines += [f"## {what}", ""]
        path = root / f"{name}.json"
        if not path.exists():
            lines += [f"Not stored yet (`{name}`): run `{command}` and store its `report.json` with `results_store`.", ""]
            continue
        report = json.loads(path.read_text())
        lines += meta_lines(report["meta"])
        lines += [f"Objective `{report.get('objective', 'rule')}`. Budget {report['budget']} episodes per search, "
                  f"rounds of {report['batch']}; "
                  f"{report['episodes_evaluated']} evaluations, {report['episodes_run']} distinct episodes run "
                  f"(the others were shared or read back), {report['wall_s'] / 60:.1f} min.", ""]
        lines += _table(report["samplers"]) + [guided_verdict(report["samplers"]), ""] + _why(report["samplers"])
        lines += _regions(report)
        for suffix, caption in (("convergence", "the lowest robustness so far, median over seeds and quartiles"),
                                ("worst", "the worst case: the camera as the attack struck, and its trace")):
            if (figures / f"{name}-{suffix}.png").exists():
                lines += [f"![{caption}](../falsify/{name}-{suffix}.png)", ""]
        lines += _worst(report) + _cases(report)
    speed = root / "falsify-speed-500.json"
    if speed.exists():
        report = json.loads(speed.read_text())
        lines += ["## Cost", ""] + meta_lines(report["meta"])
        lines += [f"{report['episodes_evaluated']} evaluations ({report['episodes_run']} distinct ODCA episodes run, "
                  f"nothing reused) took {report['wall_s'] / 60:.1f} min of wall time on this machine's 2 cores.", ""]
    lines += ["## The regression suite", "",
              "The distinct failures found for the built-in defences are shipped in `experiments/falsify/cases/`; a "
              "test replays each. After a change to a defence, `racf replay-case --suite` (or `--suite --defence NAME` "
              "for another defence) says which of them it now survives.", ""]
    reseed = root / f"{RESEED_RESULT}.json"
    if reseed.exists():
        lines += _reseeded(json.loads(reseed.read_text()))
    return "\n".join(lines)


#: The stored ``racf replay-case --suite --reseed N --json``.
RESEED_RESULT = "falsify-suite-reseed"


def _reseeded(stored: dict) -> list[str]:
    """Each suite case's parameters under other noise seeds: the parameters' failure, or one draw's."""
    from racf.stats import wilson_interval

    rows = [r for r in stored.get("replays", []) if r.get("reseeded")]
    if not rows:
        return []
    lines = ["### The parameters' failure, or one draw's?", ""] + meta_lines(stored["meta"]) + [
        "A search controls the scenario and the attack's settings; the episode's seed draws the sensors' noise and the "
        "detector's. Each case's parameters run again under other seeds: a failure the parameters make recurs, one "
        "that only its draw made does not, and no sampler can aim at it.", "",
        "| case | defence | robustness found m | other seeds that violate [95 % CI] | their median m | their lowest m |",
        "|---|---|---|---|---|---|"]
    for r in rows:
        o = r["reseeded"]
        lo, hi = wilson_interval(o["violations"], o["n"])
        lines.append(f"| `{r['case']}` | {r['defence']} | {r['robustness_then_m']:+.3f} | {o['violations']}/{o['n']} "
                     f"[{lo:.2f}, {hi:.2f}] | {o['robustness_median_m']:+.3f} | {o['robustness_min_m']:+.3f} |")
    lines.append("")
    for defence in sorted({r["defence"] for r in rows}):
        mine = [r["reseeded"] for r in rows if r["defence"] == defence]
        hits, n = sum(o["violations"] for o in mine), sum(o["n"] for o in mine)
        lo, hi = wilson_interval(hits, n)
        lines.append(f"- {defence}: its cases' parameters fail again in {hits} of {n} other draws "
                     f"({hits / n:.2f} [{lo:.2f}, {hi:.2f}]).")
    return lines + [""]
