"""Tables more than one results page draws: a sweep's settings, and SCR by attack and estimator."""

from __future__ import annotations

from racf.experiments.pages.results_format import num as _num
from racf.experiments.pages.results_format import meta_lines as _meta
from racf.experiments.pages.results_format import rate as _rate

__all__ = ["settings_table", "by_estimator_table", "split_estimator", "ESTIMATORS"]

#: The estimators the tables show as columns, in their order.
ESTIMATORS = ("raw", "ekf", "chronos", "odca")
_ESTIMATORS = ESTIMATORS


def settings_table(data: dict) -> list[str]:
    lines = _meta(data["meta"]) + [
        "| setting | N | SCR [95% CI] | ASR [95% CI] | dt_brake s, mean +- std (n) | SCR, attack before t* (n) |",
        "|---|---|---|---|---|---|"]
    for name, r in data["settings"].items():
        early = ("-" if r.get("scr_attack_before_t_star") is None else
                 f"{_rate(r['scr_attack_before_t_star'], r['scr_attack_before_t_star_ci'])} "
                 f"({r['n_attack_before_t_star']})")
        lines.append(f"| {name} | {r['n']} | {_rate(r['scr'], r['scr_ci'])} | {_rate(r.get('asr'), r.get('asr_ci'))} "
                     f"| {_num(r['dt_brake_mean'])} +- {_num(r['dt_brake_std'])} ({r['n_latency']}) | {early} |")
    return lines + [""]


def split_estimator(setting: str) -> tuple[str, str]:
    """``"clean+stealth_ramp+odca"`` -> ("stealth_ramp", "odca"); no estimator is raw depth."""
    parts = setting.split("+")
    estimator = parts.pop() if parts[-1] in _ESTIMATORS else "raw"
    attack = "+".join(p for p in parts if p != "clean") or "patch_occlusion"
    if parts[0] == "attack":
        attack = "+".join(["patch_occlusion", *parts[1:]])
    return attack, estimator


def by_estimator_table(data: dict) -> list[str]:
    """SCR per attack (rows) and estimator (columns)."""
    cells: dict[str, dict[str, dict]] = {}
    for setting, r in data["settings"].items():
        attack, estimator = split_estimator(setting)
        cells.setdefault(attack, {})[estimator] = r
    estimators = [e for e in _ESTIMATORS if any(e in row for row in cells.values())]
    lines = ["| attack | " + " | ".join(estimators) + " |", "|---|" + "---|" * len(estimators)]
    for attack, row in cells.items():
        lines.append(f"| `{attack}` | " + " | ".join(
            f"{_rate(row[e]['scr'], row[e]['scr_ci'])} (N {row[e]['n']})" if e in row else "-" for e in estimators)
            + " |")
    return lines + [""]
