"""The measured results page, written from stored results so that no number on it is typed by
hand: ``docs/results/data/*.json`` holds what the commands printed (with the command, the code
it ran on and the sensor profile), and :func:`measured_markdown` lays it out. ``make docs``
writes the page; a test checks that the committed page is the one the data gives.

To add a measurement: run its command with ``--json``, store the output beside the others
with its ``meta`` (command, commit, sensor profile), and rebuild the docs.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["measured_markdown", "SWEEPS"]

_METHODS = ("raw", "lidar", "ekf", "chronos", "softs", "nhits", "dlinear", "nlinear", "odca")


#: The stored sweep summaries the page shows, in order, with their titles.
SWEEPS = {
    "strong-1000.json": "1,000 strong-regime episodes (250 random draws, every estimator on each)",
    "spoof-1000.json": "1,000 strong-regime episodes with the LiDAR spoofed too (patch + lidar_spoof)",
    "attack-types.json": "Every attack type alone and two combined (attack-types.toml)",
    "physical-patch.json": "The printed sticker against the learned detector (physical-patch.toml)",
}


def _ci(pair) -> str:
    return "-" if not pair else f"[{pair[0]:.2f}, {pair[1]:.2f}]"


def _num(value, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def _meta(meta: dict) -> list[str]:
    extra = ", ".join(f"{k.replace('_', ' ')} {meta[k]}" for k in ("sensor_profile", "sign_geometry", "detector",
                                                                 "dataset", "draws") if k in meta)
    return [f"`{meta['command']}` on commit `{meta['commit']}` (racf {meta['racf']}), {meta['machine']}, "
            f"{meta['measured']}; {extra}.", ""]


def _settings_table(data: dict) -> list[str]:
    lines = _meta(data["meta"]) + [
        "| setting | N | SCR [95% Wilson] | ASR [95% Wilson] | dt_brake s (mean +- std, n) | SCR, attack before t* (n) |",
        "|---|---|---|---|---|---|"]
    for name, r in data["settings"].items():
        asr = "-" if r.get("asr") is None else f"{r['asr']:.2f} {_ci(r.get('asr_ci'))}"
        early = ("-" if r.get("scr_attack_before_t_star") is None else
                 f"{r['scr_attack_before_t_star']:.2f} {_ci(r['scr_attack_before_t_star_ci'])} "
                 f"({r['n_attack_before_t_star']})")
        lines.append(f"| {name} | {r['n']} | {r['scr']:.3f} {_ci(r['scr_ci'])} | {asr} | "
                     f"{_num(r['dt_brake_mean'])} +- {_num(r['dt_brake_std'])} ({r['n_latency']}) | {early} |")
    return lines + [""]


def _bench_table(data: dict) -> list[str]:
    results = data["results"]
    presets = ("weak", "mid", "strong")
    lines = _meta(data["meta"]) + [
        "RMSE in metres, the mean over the corruption draws, with its 95 % interval (test drives and draws "
        "resampled together); N is the number of scored steps per draw.", ""]
    for split, per_preset in results.items():
        lines += [f"**{split.replace('_', ' ')}**", "", "| method | " + " | ".join(presets) + " | N (strong) |",
                  "|---|" + "---|" * len(presets) + "---|"]
        methods = [m for m in _METHODS if m in per_preset["strong"]] + sorted(set(per_preset["strong"]) - set(_METHODS))
        for m in methods:
            cells = [f"{per_preset[p][m]['rmse']:.3f} {_ci(per_preset[p][m]['rmse_ci'])}" for p in presets]
            lines.append(f"| {m} | " + " | ".join(cells) + f" | {per_preset['strong'][m]['n']} |")
        lines.append("")
    return lines


def measured_markdown(data_dir: str | Path) -> str:
    """The page, from the stored results in ``data_dir``."""
    data_dir = Path(data_dir)
    load = lambda name: json.loads((data_dir / name).read_text())  # noqa: E731
    lines = ["# The latest measurements", "",
             "Written by `racf.experiments.viz.results_pages` from the stored results in `docs/results/data/`: "
             "every number here is what the command beside it printed, on the code and sensors named.", "",
             "## The paper's closed-loop table", ""]
    lines += _settings_table(load("closed-loop-table.json"))
    for name, title in SWEEPS.items():
        if (data_dir / name).exists():
            lines += [f"## {title}", ""] + _settings_table(load(name))
    lines += ["## The offline repair benchmark", ""]
    lines += _bench_table(load("offline-bench.json"))
    return "\n".join(lines)
