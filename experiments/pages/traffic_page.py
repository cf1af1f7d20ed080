"""The cross-traffic results page (``docs/results/traffic.md``), from the stored ``cross-traffic`` sweep
(the paper's settings on the empty map and with another car, paired), ``bench-traffic`` (perception
under traffic) and ``bench-sim-traffic`` (what the other cars cost)."""

from __future__ import annotations

import json
from pathlib import Path

from racf.experiments.scenarios.cross_traffic.conflict import CONFLICT_OUTCOMES
from racf.experiments.pages.results_format import meta_lines, missing, page_head, rate
from racf.experiments.sweeps.summary import setting_key

__all__ = ["traffic_markdown", "TRAFFIC_RESULTS", "crossed_key"]

#: The stored results the page reads, and the command that makes each.
TRAFFIC_RESULTS = {"cross-traffic": "racf sweep cross-traffic.toml",
                   "bench-traffic": "racf bench traffic --seeds 10 --json",
                   "bench-sim-traffic": "racf bench sim --traffic-cars 2 --steps 250 --repeats 5 --json"}


def crossed_key(setting: str, cars: int = 1, gap_s: float = 0.0, speed: float = 1.0) -> str:
    """The summary key of ``setting`` with ``cars`` other cars crossing (the cross-traffic scenario's
    parameters, as ``sweeps.summary.setting_key`` names them)."""
    return setting_key({"setting": setting, "target": "cross_traffic", "scenario_cars": cars,
                        "scenario_gap_s": gap_s, "scenario_speed": speed})


def _load(root: Path, name: str) -> dict | None:
    path = root / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None


def _sweep(data: dict) -> list[str]:
    settings = data["settings"]
    lines = meta_lines(data["meta"]) + [
        "| setting | N | SCR, empty map | SCR, with traffic | collision rate [95 % CI] | collision rate, attack "
        "before t* (N) | " + " / ".join(c.replace("_", " ") for c in CONFLICT_OUTCOMES) + " |",
        "|---|---|---|---|---|---|---|"]
    for key, r in settings.items():
        if "@" in key:
            continue
        t = settings.get(crossed_key(key))
        if t is None:
            continue
        early = "-" if t.get("n_traffic_attack_before_t_star") is None else (
            f"{rate(t['collision_rate_attack_before_t_star'], t['collision_rate_attack_before_t_star_ci'])} "
            f"({t['n_traffic_attack_before_t_star']})")
        outcomes = " / ".join(str(t["conflicts"][c]) for c in CONFLICT_OUTCOMES)
        lines.append(f"| {key} | {r['n']} | {rate(r['scr'], r['scr_ci'])} | {rate(t['scr'], t['scr_ci'])} | "
                     f"{rate(t['collision_rate'], t['collision_rate_ci'])} | {early} | {outcomes} |")
    pairs = data.get("traffic", {})
    if pairs:
        lines += ["", "**Every difference between the two maps**, episode by episode (same seed, sign and speed):", ""]
        for key, p in pairs.items():
            moved = p.get("stop_distance_change_max_m")
            where = "" if moved is None else f"; the stop distance moved by at most {moved:.3f} m"
            if not p["n_outcome_changed"]:
                lines.append(f"- `{key}`: all {p['n_pairs']} pairs end the same way{where}.")
                continue
            changes = "; ".join(f"sign {c['sign']} at {c['speed']:g} m/s, seed {c['seed']}: {c['empty']} -> "
                                f"{c['traffic']} ({c['conflict']})" for c in p["changed"])
            lines.append(f"- `{key}`: {p['n_outcome_changed']} of {p['n_pairs']} pairs end differently: {changes}.")
    lines += ["", "Why a stop moves at all when the outcome does not: the other car is sensed. Its LiDAR (the one "
              "part of a QCar 2 at the scan plane's height) puts returns beside the sign's, and the driver's "
              "resampling and the tracker's cluster shift by millimetres; the EKF, which fuses the LiDAR, then "
              "stops millimetres elsewhere. At sign 0, a corner no lane joins, a car that ran the line goes on "
              "into the turn beside the oncoming car: it drifts into it, or passes with the footprints touching "
              "(a near miss, TTC 0)."]
    return lines + [""]


def _perception(data: dict) -> list[str]:
    lines = meta_lines(data["meta"]) + [
        f"Clean approaches at 1 m/s, {data['seeds']} seeds per row, each run on the empty map and with the other "
        f"car. Recall: the detector's, over the steps the sign is in view; off: the share of those steps whose "
        f"depth distance or LiDAR reference was more than {data['off_m']} m from d_true.", "",
        "| case | estimator | map | SCR [95 % CI] | collisions | recall | depth off | LiDAR off |",
        "|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        for name in ("empty", "traffic"):
            x = r[name]
            lines.append(f"| {r['case']} | {r['estimator']} | {name} | {rate(x['scr'], x['scr_ci'])} | "
                         f"{x['collisions']} | {x['recall']:.3f} | {x['depth_off_share']:.3f} | "
                         f"{x['lidar_off_share']:.3f} |")
    lines += ["", "The cases: " + "; ".join(f"`{r['case']}`: {r['about']}" for r in data["rows"][::2]) + "."]
    return lines + [""]


def _cost(data: dict) -> list[str]:
    empty = ", ".join(f"{v:.2f}" for v in data["rtf_empty"])
    crossed = ", ".join(f"{v:.2f}" for v in data["rtf_traffic"])
    return meta_lines(data["meta"]) + [
        "The full sensor set at 320 x 240 on an approach to sign 3, timed in alternation in one process.", "",
        "| map | real-time factor, each run |", "|---|---|", f"| empty | {empty} |",
        f"| {data['cars']} other cars | {crossed} |", "",
        f"Ratio with / without, median over the pairs: **{data['ratio']:.3f}** (a drop of "
        f"{100 * (1 - data['ratio']):.1f} %; the goal is at most 25 %).", ""]


def traffic_markdown(root: Path) -> str:
    """The page from the stored results in ``root`` (``docs/results/data``)."""
    root = Path(root)
    lines = page_head(
        "Cross-traffic at the stop signs",
        "Another QCar 2 drives through each sign's conflict point when the ego car would have, had it not "
        "stopped ([the concepts page](../concepts/traffic.md) says how it is placed and timed, and what the "
        "referee scores). A missed stop is then scored by what it meets.")
    for name, title, section in (("cross-traffic", "The paper's settings, on the empty map and with traffic", _sweep),
                                 ("bench-traffic", "Perception under traffic", _perception),
                                 ("bench-sim-traffic", "What the other cars cost", _cost)):
        lines += [f"## {title}", ""]
        data = _load(root, name)
        lines += section(data) if data is not None else missing(name, TRAFFIC_RESULTS[name])
    return "\n".join(lines)
