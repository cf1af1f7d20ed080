"""What cross-traffic adds to a sweep's report (``CrossTraffic.report``): the collision rate, conflict
outcomes and smallest time-to-collision per setting with other cars, and every episode run on both
maps (the paired control with ``cars = 0`` and the same seed) whose outcome changed (``traffic.json``)."""

from __future__ import annotations

import pandas as pd

from racf.stats import cell as _fmt
from racf.stats import cell_ci as _ci

__all__ = ["traffic_pairs", "traffic_lines", "report"]


def traffic_pairs(frame: pd.DataFrame) -> dict:
    """Per setting, the episodes run on both maps (same seed and cell), and how their outcomes differ:
    ``traffic.json``, the evidence for explaining every difference between the two."""
    if "traffic_cars" not in frame or not (frame["traffic_cars"].fillna(0) > 0).any():
        return {}
    keys = ["setting", "seed", "sign", "speed"]
    empty = frame[frame["traffic_cars"].fillna(0) == 0].set_index(keys)
    crossed = frame[frame["traffic_cars"].fillna(0) > 0].set_index(keys)
    both = empty.join(crossed, how="inner", lsuffix="_empty", rsuffix="_traffic")
    out = {}
    for setting, rows in both.groupby(level="setting", sort=True):
        changed = rows[(rows["success_empty"] != rows["success_traffic"])
                       | (rows["failure_empty"].fillna("") != rows["failure_traffic"].fillna(""))]
        out[str(setting)] = {
            "n_pairs": int(len(rows)), "n_outcome_changed": int(len(changed)),
            "changed": [{"seed": int(i[1]), "sign": int(i[2]), "speed": float(i[3]),
                         "empty": r["failure_empty"] or "success", "traffic": r["failure_traffic"] or "success",
                         "conflict": r["conflict_traffic"], "collision_with": r["collision_with_traffic"]}
                        for i, r in changed.iterrows()],
            "stop_distance_change_max_m": float((rows["stop_distance_m_traffic"] - rows["stop_distance_m_empty"])
                                                .abs().max()) if rows["stop_distance_m_traffic"].notna().any() else None}
    return out


def traffic_lines(summary: dict) -> list[str]:
    """The cross-traffic table: collision rate, conflict outcomes, smallest TTC (only with traffic)."""
    rows = {k: r for k, r in summary.items() if r.get("n_traffic")}
    if not rows:
        return []
    lines = ["", "With cross-traffic (`scenarios.cross_traffic`): collision rate [95 % Wilson CI] over all episodes and "
             "over those whose attack began before t*; the conflict outcomes; the median smallest "
             "time-to-collision.", "",
             "| setting | N | collision rate | collision rate, attack before t* (N) | collision / crash / near miss / "
             "passed / yielded | min TTC s, median |", "|---|---|---|---|---|---|"]
    for key, r in rows.items():
        early = "—" if r.get("n_traffic_attack_before_t_star") is None else (
            f"{_fmt(r['collision_rate_attack_before_t_star'])} {_ci(r['collision_rate_attack_before_t_star_ci'])} "
            f"({r['n_traffic_attack_before_t_star']})")
        outcomes = " / ".join(str(v) for v in r["conflicts"].values())
        lines.append(f"| {key} | {r['n_traffic']} | {_fmt(r['collision_rate'])} {_ci(r['collision_rate_ci'])} | "
                     f"{early} | {outcomes} | {_fmt(r['min_ttc_median_s'])} |")
    return lines


def report(frame: pd.DataFrame, summary: dict) -> tuple[list[str], dict[str, dict]]:
    """The report's cross-traffic lines, and ``traffic.json`` (the pairs) when the rows hold both maps."""
    lines = traffic_lines(summary)
    pairs = traffic_pairs(frame) if not frame.empty else {}
    if not pairs:
        return lines, {}
    lines += ["", "The same episodes on both maps (`traffic.json` lists each whose outcome changed):", "",
              "| setting | pairs | outcome changed | largest change of the stop distance m |", "|---|---|---|---|"]
    lines += [f"| {k} | {p['n_pairs']} | {p['n_outcome_changed']} | {_fmt(p['stop_distance_change_max_m'], 3)} |"
              for k, p in pairs.items()]
    return lines, {"traffic.json": pairs}
