"""The sweep's report: a Markdown summary (N, SCR and ASR with Wilson intervals per setting, the SCR
over the episodes whose attack began before t*, and SCR per attack x estimator; with kept logs,
the detector's recall by distance band) and plots of SCR against rho and against T_atk with
Wilson bands.
``racf sweep --report DIR`` redraws it from the stored parts without running anything."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from racf.experiments.sweeps.detection_bands import band_labels, recall_rows
from racf.provenance import atomic_write
from racf.experiments.sweeps.store import ResultStore
from racf.stats import median_ci, wilson_interval
from racf.experiments.episode.spec import parse_setting
from racf.experiments.metrics.criteria import criteria_of_rows, scenarios_of
from racf.stats import cell as _fmt
from racf.stats import cell_ci as _ci
from racf.experiments.sweeps.summary import plugin_measures, setting_key, stealth_summary, summarize_settings

__all__ = ["write_report", "report_from_store", "stealth_rows"]


def _rate(success: pd.Series) -> dict:
    n, k = int(len(success)), int(success.sum())
    lo, hi = wilson_interval(k, n)
    return {"n": n, "scr": k / n if n else None, "scr_ci": [lo, hi]}


def _bins(values: pd.Series, max_bins: int = 6) -> pd.Series:
    """Grid values as they are; many distinct values (random sweeps) into quantile bins labelled by their mean."""
    if values.nunique() <= max_bins:
        return values.astype(float)
    codes = pd.qcut(values, max_bins, labels=False, duplicates="drop")
    return values.groupby(codes).transform("mean")


def _band_plot(frame: pd.DataFrame, column: str, point, path: Path, *, xlabel: str, ylabel: str, title: str,
               log_x: bool = False, log_y: bool = False, ylim: tuple[float, float] | None = None) -> Path:
    """One line per (attack, estimator) against ``column`` (binned), with a shaded interval:
    ``point(rows)`` gives (value, low, high) for one bin's rows, or None to skip it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    x = _bins(frame[column])
    for (attack, estimator), rows in frame.assign(_x=x).groupby(["attack", "estimator"], sort=True):
        pts = [(xv, *p) for xv, g in rows.groupby("_x", sort=True) if (p := point(g)) is not None]
        if not pts:
            continue
        xs, ys, lo, hi = map(np.array, zip(*pts))
        line, = ax.plot(xs, ys, marker="o", label=f"{attack} / {estimator}")
        ax.fill_between(xs, lo, hi, color=line.get_color(), alpha=0.15)
    if log_x:
        ax.set_xscale("log")
    if log_y:
        ax.set_yscale("log")
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, which="both" if log_y else "major")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, title="attack / estimator", title_fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _scr_point(rows: pd.DataFrame):
    r = _rate(rows["success"].astype(bool))
    return r["scr"], *r["scr_ci"]


def _undetected_point(rows: pd.DataFrame):
    median, ci = median_ci(rows["undetected_error_m"])
    return None if median is None else (median, *ci)


def _plot(frame: pd.DataFrame, column: str, label: str, path: Path) -> Path:
    return _band_plot(frame, column, _scr_point, path, xlabel=label, ylabel="stop compliance (SCR)",
                      title=f"SCR against {label} (95 % Wilson bands)", ylim=(-0.02, 1.02))


def stealth_rows(frame: pd.DataFrame) -> list[dict]:
    """The stealth measures per attack, its settings and estimator (``scoring.stealth``), as data:
    what ``stealth.json`` stores and the summary's stealth table shows."""
    attacked = frame[frame["attack"] != "none"]
    if attacked.empty or "undetected_error_m" not in attacked:
        return []
    attacked = attacked.assign(attack_params=attacked.get("attack_params", pd.Series("", index=attacked.index))
                               .fillna(""))
    rows_out = []
    for (attack, params, estimator), rows in attacked.groupby(["attack", "attack_params", "estimator"], sort=True):
        rows_out.append({"attack": str(attack), "params": str(params), "estimator": str(estimator),
                         **_rate(rows["success"].astype(bool)), **stealth_summary(rows)})
    return rows_out


def _stealth_lines(frame: pd.DataFrame, out: Path, paths: dict) -> list[str]:
    """The stealth table (per attack, its settings and estimator) and, where the sweep varies
    an attack's rate, the undetected error against the rate and against the duration."""
    rows = stealth_rows(frame)
    if not rows:
        return []
    atomic_write(out / "stealth.json", json.dumps(rows, indent=1, allow_nan=False))
    lines = ["", "Stealth, per attack, its settings and estimator (`scoring.stealth`): SCR; the undetected error "
             "(largest |d_fused - d_true| before the defence's first flag) as median [95 % bootstrap CI] and max; "
             "the share of attacks the defence flagged [Wilson CI]; the median detection delay. Raw depth has no "
             "detector: its error is the attack's whole effect.", "",
             "| attack | settings | estimator | N | SCR [95 % CI] | undetected error m, median [CI] | max | "
             "flagged [CI] | delay s |", "|---|---|---|---|---|---|---|---|---|"]
    for st in rows:
        lines.append(f"| {st['attack']} | {st['params'] or '—'} | {st['estimator']} | {st['n']} | "
                     f"{_fmt(st['scr'])} {_ci(st['scr_ci'])} | "
                     f"{_fmt(st.get('undetected_error_median'), 3)} {_ci3(st.get('undetected_error_ci'))} | "
                     f"{_fmt(st.get('undetected_error_max'), 3)} | {_fmt(st.get('detected_share'))} "
                     f"{_ci(st.get('detected_share_ci', [None, None]))} | "
                     f"{_fmt(st.get('detection_delay_median'), 3)} |")
    attacked = frame[frame["attack"] != "none"]
    if "param_rate_mps" in attacked and attacked["param_rate_mps"].notna().any():
        ramps = attacked[attacked["param_rate_mps"].notna()]
        paths["undetected_vs_rate"] = _stealth_plot(ramps, "param_rate_mps", "attack rate r (m/s)",
                                                    out / "undetected_vs_rate.png", log_x=True)
        paths["undetected_vs_t_atk"] = _stealth_plot(ramps, "t_atk_set", "attack duration T_atk (s)",
                                                     out / "undetected_vs_t_atk.png")
        lines += ["", "![undetected error vs r](undetected_vs_rate.png) "
                  "![undetected error vs T_atk](undetected_vs_t_atk.png)"]
    return lines


def _recall_lines(frame: pd.DataFrame, out: Path) -> list[str]:
    """The detector's recall by the target's distance, from the kept per-step logs (``recall.json``)."""
    rows = recall_rows(frame, out / "logs")
    if not rows:
        return []
    atomic_write(out / "recall.json", json.dumps(rows, indent=1, allow_nan=False))
    labels = band_labels()
    lines = ["", "Detection recall by the target's true depth (`detection_bands`): control steps with a new frame "
             "and the target in view (attacked settings: the steps the attack acted on); recall [95 % Wilson CI] "
             "(frames).", "", "| attack | settings | estimator | " + " | ".join(labels) + " |",
             "|---|---|---|" + "---|" * len(labels)]
    for r in rows:
        cells = [f"{_fmt(b['recall'])} {_ci(b['recall_ci'])} ({b['n']})" if b["n"] else "—"
                 for b in (r["bands"][label] for label in labels)]
        lines.append(f"| {r['attack']} | {r['params'] or '—'} | {r['estimator']} | " + " | ".join(cells) + " |")
    return lines


def _stealth_plot(frame: pd.DataFrame, column: str, label: str, path: Path, log_x: bool = False) -> Path:
    return _band_plot(frame, column, _undetected_point, path, xlabel=label, ylabel="undetected error (m)",
                      title=f"Undetected error against {label}: median, 95 % bootstrap band", log_x=log_x, log_y=True)


def _ci3(ci) -> str:
    return "[—, —]" if not ci or ci[0] is None else f"[{_fmt(ci[0], 3)}, {_fmt(ci[1], 3)}]"


def _robustness_cells(r: dict) -> str:
    """The stop rule's robustness cells of a setting's summary ('—' for rows stored before it was logged)."""
    if r.get("robustness_median_m") is None:
        return "— | —"
    return (f"{_fmt(r['robustness_median_m'], 3)} {_ci3(r['robustness_ci'])} ({_fmt(r['robustness_min_m'], 3)}) | "
            f"{_fmt(r['violation_share'])} {_ci(r['violation_share_ci'])}")


def _plugin_metric_lines(frame: pd.DataFrame) -> list[str]:
    """A table of what the plug-in metrics the episodes scored say, per setting and scenario parameters
    (as each declares it)."""
    rows = []
    if not frame.empty:
        keys = pd.Series([setting_key(row) for row in frame.to_dict("records")], index=frame.index)
        for key, group in frame.groupby(keys, sort=True):
            attacked = bool(parse_setting(str(group["setting"].iloc[0]))[0])
            rows += [f"| {key} | {m['measure']} | {_fmt(m['value'], 3)} {_ci(m['ci'])} | {m['n']} |"
                     for m in plugin_measures(group, attacked)]
    if not rows:
        return []
    return ["", "Plug-in metrics (each field as its metric declares it; 95 % intervals):", "",
            "| setting | measure | value [95 % CI] | N |", "|---|---|---|---|", *rows]


def _criteria_lines(frame: pd.DataFrame, summary: dict) -> list[str]:
    """Each criterion of the rows' scenarios: its pass rate where its rule applies, per setting and
    scenario parameters (the stop rule where a sign stands, no needless stop where none does, ...)."""
    criteria = criteria_of_rows(frame) if not frame.empty else []
    rows = [f"| {key} | {c.name} | {_fmt(r[f'{c.name}_rate'])} {_ci(r[f'{c.name}_rate_ci'])} | {r[f'n_{c.name}']} |"
            for key, r in summary.items() for c in criteria if r.get(f"n_{c.name}")]
    if not rows:
        return []
    return ["", "Criteria (the scenarios' rules, each where it applies: passed share [95 % Wilson CI], N):", "",
            "| setting | criterion | passed [95 % CI] | N |", "|---|---|---|---|", *rows]


def _scr_cells(r: dict) -> str:
    """A summary's SCR cell: its rate and interval, or why it has none (no sign stood)."""
    if r.get("n_scr") == 0:
        return "— (no sign stands)"
    return f"{_fmt(r['scr'])} {_ci(r['scr_ci'])}"


def write_report(frame: pd.DataFrame, out: Path, name: str = "sweep") -> dict[str, Path]:
    """Writes ``summary.md``, ``summary.json`` and the two plots under ``out``."""
    out = Path(out)
    paths = {}
    summary = summarize_settings(frame)
    atomic_write(out / "summary.json", json.dumps(summary, indent=1, allow_nan=False))
    stopped = {setting: r for setting, r in summary.items() if "scr" in r}  # where the stop rule was judged
    lines = [f"# Sweep `{name}`", "", f"{len(frame)} episodes."]
    if stopped:
        lines += _stop_rule_lines(stopped)
    lines += _criteria_lines(frame, summary)
    lines += _plugin_metric_lines(frame)
    for scenario in scenarios_of(frame):  # what each scenario the rows ran adds (its own tables and files)
        more, files = scenario().report(frame, summary)
        lines += more
        for file, data in files.items():
            atomic_write(out / file, json.dumps(data, indent=1, allow_nan=False))
    if not frame.empty and "success" in frame:
        lines += _by_attack_lines(frame)
        lines += _stealth_lines(frame, out, paths)
        lines += _recall_lines(frame, out)
        paths["scr_vs_rho"] = _plot(frame, "rho_set", "patch coverage rho", out / "scr_vs_rho.png")
        paths["scr_vs_t_atk"] = _plot(frame, "t_atk_set", "attack duration T_atk (s)", out / "scr_vs_t_atk.png")
        lines += ["", "![SCR vs rho](scr_vs_rho.png) ![SCR vs T_atk](scr_vs_t_atk.png)"]
    paths["summary"] = atomic_write(out / "summary.md", "\n".join(lines) + "\n")
    return paths


def _stop_rule_lines(summary: dict) -> list[str]:
    """The stop rule's table: a row per setting whose episodes it judged."""
    lines = [f"SCR with its 95 % Wilson interval; ASR = 1 - SCR "
             "under an attack; SCR, attack before t*: over the episodes whose attack began before t* (only "
             "those can test a defence), with their count; dt_brake over successful stops; largest jump: the "
             "largest step change of the distance the car acted on beyond its own motion, over all episodes; "
             "STL robustness: the stop rule's (negative: broken), its median [95 % CI] and lowest, and the "
             "share of episodes that broke it.", "",
             "| setting | N | SCR [95 % CI] | ASR | SCR, attack before t* (N) | dt_brake s (n) | largest jump m | "
             "robustness m, median (lowest) | rule broken [95 % CI] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for setting, r in summary.items():
        early = "—" if r.get("n_attack_before_t_star") is None else (
            f"{_fmt(r['scr_attack_before_t_star'])} {_ci(r['scr_attack_before_t_star_ci'])} "
            f"({r['n_attack_before_t_star']})")
        lines.append(f"| {setting} | {r['n']} | {_scr_cells(r)} | {_fmt(r['asr'])} | {early} | "
                     f"{_fmt(r['dt_brake_mean'], 3)} ({r['n_latency']}) | {_fmt(r['max_fused_jump_m'], 3)} | "
                     f"{_robustness_cells(r)} |")
    return lines


def _by_attack_lines(frame: pd.DataFrame) -> list[str]:
    """SCR by attack (rows) and estimator (columns), where a sign stood."""
    frame = frame.assign(estimator=frame["estimator"].astype(str))
    lines = ["", "By attack and estimator (columns):", ""]
    estimators = sorted(frame["estimator"].unique())
    lines += ["| attack | " + " | ".join(estimators) + " |", "|---|" + "---|" * len(estimators)]
    for attack, rows in frame.groupby("attack", sort=True):
        cells = []
        for e in estimators:
            g = rows[(rows["estimator"] == e) & rows["success"].notna()]  # where a sign stood
            r = _rate(g["success"].astype(bool)) if len(g) else None
            cells.append(f"{_fmt(r['scr'])} (N {r['n']})" if r else "—")
        lines.append(f"| {attack} | " + " | ".join(cells) + " |")
    return lines


def report_from_store(out: str | Path) -> dict[str, Path]:
    """Redraws the report of a stored sweep (no episode runs): from the episodes of its spec as this
    code makes them (a folder also holds the results of older code, under other ids: never mixed in).
    ValueError when some were never run by this code (run the sweep again: it runs only those)."""
    from racf.experiments.sweeps.spec import parse_spec

    out = Path(out)
    if not (out / "sweep.json").exists():
        raise ValueError(f"{out} is not a sweep folder (no sweep.json; `racf sweep SPEC --out {out}` makes one)")
    spec_file = out / "spec.toml"
    if not spec_file.exists():
        raise ValueError(f"{out} has no spec.toml: cannot tell which of its results the sweep is")
    spec = parse_spec(spec_file.read_text(), str(spec_file))
    store = ResultStore(out)
    ids = [e.trial_id for e in spec.episodes()]
    missing = [i for i in ids if not (store.parts / f"{i}.parquet").exists()]
    if missing:
        raise ValueError(f"{out}: {len(missing)} of its {len(ids)} episodes were not run by this code (e.g. "
                         f"{missing[0]}); `racf sweep {spec_file} --out {out}` runs just those")
    return write_report(store.rows(ids).sort_values("trial_id", ignore_index=True), out, spec.name)
