"""Figures of the offline benchmark (matplotlib, PNG): diagnostics heatmap, resilience radar,
complexity, the qualitative strong-preset trace and the recovery bars."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_all"]

_COLORS = {"raw": "#7f7f7f", "lidar": "#17becf", "ekf": "#9467bd", "chronos": "#ff7f0e", "softs": "#8c564b",
           "nhits": "#e377c2", "dlinear": "#bcbd22", "nlinear": "#2ca02c", "odca": "#1f77b4"}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def write_all(results: dict, traces: dict, folder: Path) -> dict[str, Path]:
    folder = Path(folder)
    splits = [s for s in ("by_series", "leave_target_out") if s in results]
    paths = {}
    for split in splits:
        paths[f"recovery_{split}"] = recovery_bars(results, split, folder / f"recovery_{split}.png")
        paths[f"diagnostics_{split}"] = diagnostics_heatmap(results, split, folder / f"diagnostics_{split}.png")
    first = splits[0]
    if len(results[first]) >= 2:
        paths["radar"] = radar(results, first, folder / "resilience_radar.png")
    if results.get("complexity") and "strong" in results[first]:
        paths["complexity"] = complexity(results, folder / "complexity.png")
    if (first, "strong") in traces:
        paths["qualitative"] = qualitative(traces[(first, "strong")]["frame"], folder / "qualitative_strong.png")
    return paths


def recovery_bars(results: dict, split: str, path: Path) -> Path:
    plt = _plt()
    presets = list(results[split])
    methods = list(results[split][presets[0]])
    fig, ax = plt.subplots(figsize=(8, 3.6))
    width = 0.8 / len(methods)
    for i, m in enumerate(methods):
        x = np.arange(len(presets)) + (i - len(methods) / 2 + 0.5) * width
        y = [results[split][p][m]["rmse"] or np.nan for p in presets]
        ci = [results[split][p][m].get("rmse_ci") or [np.nan, np.nan] for p in presets]
        err = np.abs(np.array([[yy - c[0], c[1] - yy] for yy, c in zip(y, ci)]).T)
        ax.bar(x, y, width, color=_COLORS.get(m), label=m, yerr=err, capsize=2, error_kw={"lw": 0.7})
    ax.set_xticks(np.arange(len(presets)), presets)
    ax.set_ylabel("RMSE vs d_clean (m)")
    ax.set_title(f"Recovery by preset, {split.replace('_', ' ')} split (95 % CI over test series)")
    ax.legend(ncol=5, fontsize=7, loc="upper left")
    ax.grid(axis="y", alpha=0.3)
    return _save(fig, path)


def diagnostics_heatmap(results: dict, split: str, path: Path) -> Path:
    plt = _plt()
    presets = list(results[split])
    methods = list(results[split][presets[0]])
    cols = [(metric, p) for metric in ("auroc_xs", "auprc_xs", "auroc_chg", "auprc_chg") for p in presets]
    grid = np.array([[results[split][p][m].get(metric) if results[split][p][m].get(metric) is not None else np.nan
                      for metric, p in cols] for m in methods], float)
    fig, ax = plt.subplots(figsize=(1.0 + 0.62 * len(cols), 0.9 + 0.38 * len(methods)))
    im = ax.imshow(grid, cmap="viridis", vmin=0, vmax=1, aspect="auto")
    for i in range(grid.shape[0]):
        for j in range(grid.shape[1]):
            if np.isfinite(grid[i, j]):
                ax.text(j, i, f"{grid[i, j]:.2f}", ha="center", va="center", fontsize=7,
                        color="white" if grid[i, j] < 0.6 else "black")
    ax.set_xticks(range(len(cols)), [f"{m.split('_')[0].upper()} {m.split('_')[1].upper()}\n{p}" for m, p in cols],
                  fontsize=7)
    ax.set_yticks(range(len(methods)), methods)
    ax.set_title(f"Attack diagnostics, {split.replace('_', ' ')} split (XS = |est - LiDAR|, Chg = |est - d~|)",
                 fontsize=9)
    fig.colorbar(im, ax=ax, fraction=0.03)
    return _save(fig, path)


def _minmax(values: np.ndarray, higher_is_better: bool) -> np.ndarray:
    v = np.asarray(values, float)
    lo, hi = np.nanmin(v), np.nanmax(v)
    scaled = np.full_like(v, 1.0) if hi - lo < 1e-12 else (v - lo) / (hi - lo)
    return np.nan_to_num(scaled if higher_is_better else 1 - scaled, nan=0.0)


def radar(results: dict, split: str, path: Path) -> Path:
    """Axes (min-max scaled across methods, outer is better): RMSE per preset, BD (inverted), RGR."""
    plt = _plt()
    presets = list(results[split])
    methods = [m for m in results[split][presets[0]] if m != "raw"]
    axes = [f"RMSE {p}" for p in presets] + ["BD (inv.)", "RGR"]
    raw = np.array([[results[split][p][m]["rmse"] for p in presets]
                    + [results["derived"][split][m]["bd"], results["derived"][split][m]["rgr"]] for m in methods],
                   float)
    scaled = np.column_stack([_minmax(raw[:, j], higher_is_better=(j == raw.shape[1] - 1))
                              for j in range(raw.shape[1])])
    angles = np.linspace(0, 2 * np.pi, len(axes), endpoint=False)
    fig = plt.figure(figsize=(5.2, 5.2))
    ax = fig.add_subplot(projection="polar")
    for m, row in zip(methods, scaled):
        ax.plot(np.r_[angles, angles[0]], np.r_[row, row[0]], color=_COLORS.get(m), label=m,
                lw=2.2 if m == "odca" else 1.0)
        if m == "odca":
            ax.fill(np.r_[angles, angles[0]], np.r_[row, row[0]], color=_COLORS[m], alpha=0.15)
    ax.set_xticks(angles, axes, fontsize=8)
    ax.set_yticks([0.25, 0.5, 0.75, 1.0], [], fontsize=6)
    ax.set_title("Resilience summary (outer is better; scaled across methods)", fontsize=9)
    ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.95, -0.05))
    return _save(fig, path)


def complexity(results: dict, path: Path) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.6, 3.8))
    for m, row in results["complexity"].items():
        if row.get("rmse_strong") is None:
            continue
        x = max(row["total"], 1)
        ax.scatter(x, row["rmse_strong"], color=_COLORS.get(m), s=60 if m == "odca" else 30, zorder=3)
        ax.annotate(f"{m} ({row['trainable']:,} trainable)", (x, row["rmse_strong"]), fontsize=7,
                    xytext=(4, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_xlabel("total parameters (log)")
    ax.set_ylabel("strong-preset RMSE (m)")
    ax.set_title("Complexity vs repair accuracy (strong)", fontsize=9)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def qualitative(frame, path: Path) -> Path:
    """One test drive under the strong preset: the clean reference, the attacked input, Chronos-only and ODCA."""
    plt = _plt()
    scored = np.isfinite(frame["d_clean"].to_numpy()) & np.isfinite(frame["est_raw"].to_numpy())
    hit = scored & (frame["label"].to_numpy() == 1)
    # The approach (a run of scored steps, gaps under 0.5 s bridged) with the most corrupted steps.
    sid = frame["series_id"].to_numpy()
    run = np.cumsum(np.r_[True, sid[1:] != sid[:-1]] | _gap_starts(scored, 25))
    counts = np.bincount(run, weights=hit)
    best = int(np.argmax(counts)) if counts.size else 0
    rows = np.flatnonzero((run == best) & scored)
    rows = rows if rows.size else np.arange(len(frame))
    s = frame.iloc[max(rows[0] - 25, 0):rows[-1] + 26]
    s = s[s["series_id"] == sid[rows[0]]]
    sid = sid[rows[0]]
    fig, ax = plt.subplots(figsize=(9, 3.4))
    t = s["t"].to_numpy()
    label = s["label"].to_numpy()
    edges = np.flatnonzero(np.diff(np.r_[0, label, 0]))
    for k, (a, b) in enumerate(zip(edges[::2], edges[1::2])):
        ax.axvspan(t[a], t[min(b, len(t) - 1)], color="red", alpha=0.08, label="corrupted" if k == 0 else None)
    ax.plot(t, s["d_clean"], color="black", lw=1.6, label="d_clean (reference)")
    ax.plot(t, s["d_meas"], color="gray", ls="--", lw=1.0, label="attacked input d~")
    ax.plot(t, s["est_chronos"], color=_COLORS["chronos"], lw=1.0, label="Chronos-2 forecast-only")
    ax.plot(t, s["est_odca"].where(np.isfinite(s["d_clean"])), color=_COLORS["odca"], lw=1.4, label="ODCA")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("distance (m)")
    ax.set_title(f"Strong preset, test drive {sid}", fontsize=9)
    ax.legend(fontsize=7, ncol=3, loc="upper right")
    ax.grid(alpha=0.3)
    return _save(fig, path)


def _gap_starts(scored: np.ndarray, min_gap: int) -> np.ndarray:
    """True at the first scored step after at least ``min_gap`` unscored steps (a new approach)."""
    out = np.zeros(len(scored), bool)
    gap = min_gap
    for i, ok in enumerate(scored):
        if ok:
            out[i] = gap >= min_gap
            gap = 0
        else:
            gap += 1
    return out


def _save(fig, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    _plt().close(fig)
    return path
