"""The moment that matters in an episode, as one picture: what the camera showed and what the depth
read when the attack acted and the defence answered, beside the distances over the whole approach
with that instant marked. Drawn from the episode itself (run again from its spec: episodes
reproduce to the bit), so no viewer, cursor or tooltip is involved.

``racf moment`` makes it for any episode: ``racf trial``'s flags name one, or ``--sweep FOLDER
--episode ID`` one of a sweep's. The moment (``choose_moment``) is, in this order of preference:
the attacked step where the defence's distance departs most from the attacked depth while the sign
is in view (the defence answering); else the first attacked step with the sign in view, a third of
a second on (the attack acting); else the brake's onset; else the step nearest the sign.
"""

from __future__ import annotations

import itertools
import math
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["Moment", "Target", "SIGN", "LEAD", "target_of", "choose_moment", "moment_figure", "episode_outcome",
           "gaps_caption"]

#: How long after an attack starts its effect is shown where no defence answers, s.
_SETTLE_S = 0.33


@dataclass(frozen=True)
class Target:
    """What the episode measures a distance to: its columns, and how the picture names them."""

    noun: str
    truth: str
    meas: str
    lidar: str
    fused: str
    truth_label: str


SIGN = Target("the sign", "d_true", "d_meas", "lidar", "d_fused",
              "the camera's depth to the sign, in view (the referee's d_true)")
LEAD = Target("the car ahead", "lead_gap", "lead_d_meas", "lead_lidar", "lead_d_fused",
              "the camera to the car ahead's rear, along its axis (the referee's)")


def target_of(log: pd.DataFrame, targets=()) -> tuple[Target, pd.DataFrame]:
    """The car ahead where the episode follows one: the first vehicle its world declares
    (``WorldTarget``) that was in the world while the following stage gave a distance, with the
    truth added to the log as ``lead_gap``: from the car's camera to the lead's rear along the
    camera's axis, the reference its depth and its defence measure from (the picture draws every
    distance from one reference); else the sign (``d_true``: the camera's depth to it already)."""
    if np.isfinite(_col(log, LEAD.fused)).any():
        from racf.sim.sensors.calibration import car_build

        cx, cy = car_build(320, 240).camera_xy_m
        for declared in targets:
            x, y = (_col(log, c) for c in declared.pose_columns[:2])
            if declared.kind == "vehicle" and np.isfinite(x).any():
                yaw = _col(log, "yaw")
                c, s = np.cos(yaw), np.sin(yaw)
                cam_x, cam_y = _col(log, "x") + c * cx - s * cy, _col(log, "y") + s * cx + c * cy
                gap = (x - cam_x) * c + (y - cam_y) * s - declared.size_m[0] / 2
                return LEAD, log.assign(lead_gap=gap)
    return SIGN, log


@dataclass(frozen=True)
class Moment:
    step: int
    t: float
    why: str


def _col(log: pd.DataFrame, name: str) -> np.ndarray:
    return log[name].to_numpy(float) if name in log else np.full(len(log), np.nan)


def choose_moment(log: pd.DataFrame, target: Target = SIGN) -> Moment:
    """The step to show (see the module's docstring), from an episode's step log."""
    if log.empty:
        raise ValueError("the episode log is empty: there is no moment to show")
    t = log["t"].to_numpy(float)
    attacked = _flag(log, "attack_active")
    in_view = np.isfinite(_col(log, target.truth))
    if target is SIGN and "sign_in_view" in log:
        in_view &= _flag(log, "sign_in_view")
    fused, meas = _col(log, target.fused), _col(log, target.meas)
    # The defence answers where it gives a distance the attacked depth does not: another, or one where there is none.
    answered = attacked & in_view & np.isfinite(fused) & (~np.isfinite(meas) | (np.abs(fused - meas) > 0.05))
    if answered.any():
        steps = np.flatnonzero(answered)
        gap = np.abs(fused - meas)[steps]
        if np.isfinite(gap).any():
            step = int(steps[np.nanargmax(gap)])
        else:  # the depth is gone (the target hidden from it): a moment into the repair
            step = int(steps[t[steps] <= t[steps[0]] + _SETTLE_S][-1])
        return Moment(step, float(t[step]), "the attack acts and the defence answers")
    acting = np.flatnonzero(attacked & in_view)
    if acting.size:
        step = int(acting[t[acting] <= t[acting[0]] + _SETTLE_S][-1])
        return Moment(step, float(t[step]), "the attack acts")
    brake = np.flatnonzero(_flag(log, "brake"))
    if brake.size:
        return Moment(int(brake[0]), float(t[brake[0]]), "the car brakes")
    d = np.where(in_view, _col(log, target.truth), np.nan)
    step = int(np.nanargmin(d)) if np.isfinite(d).any() else len(log) // 2
    return Moment(step, float(t[step]), f"the car nearest {target.noun}")


def _flag(log: pd.DataFrame, name: str) -> np.ndarray:
    return log[name].fillna(False).astype(bool).to_numpy() if name in log else np.zeros(len(log), bool)


def _frame_at(spec, step: int) -> dict:
    """What the car saw at ``step`` (after the attacks), the same frame without them, the pixels the
    attack changed and the car's step row, by running the episode again."""
    from racf.experiments.episode import run_trial

    seen: dict = {}
    steps = itertools.count()

    def keep(env, obs, info, row) -> None:
        if next(steps) == step:
            clean = env.unwrapped.sensor_observation()  # the world without the attack: for the referee's eye
            changed = np.any(obs["rgb"] != clean["rgb"], axis=-1) | (obs["depth"][..., 0] != clean["depth"][..., 0])
            seen.update(rgb=obs["rgb"].copy(), clean=clean["rgb"].copy(), depth=obs["depth"][..., 0].copy(),
                        changed=changed, row=dict(row))

    run_trial(spec, on_step=keep)
    if not seen:
        raise ValueError(f"the episode ran fewer than {step + 1} steps this time: it did not reproduce")
    return seen


def _detection(row: dict) -> tuple[float, float, float, float] | None:
    """The car's detection box at that step (x0, y0, x1, y1 px), or None where it had none."""
    box = tuple(row.get(k, math.nan) for k in ("det_x0", "det_y0", "det_x1", "det_y1"))
    return box if all(isinstance(v, (int, float)) and math.isfinite(v) for v in box) else None


def _crop(frame: dict, shape: tuple[int, int]) -> tuple[slice, slice]:
    """Where to look: the attack's pixels and the car's detection, with room around them (the whole
    frame where there is neither)."""
    boxes = []
    if frame["changed"].any():
        rows, cols = np.nonzero(frame["changed"])
        boxes.append((cols.min(), rows.min(), cols.max() + 1, rows.max() + 1))
    det = _detection(frame["row"])
    if det is not None:
        boxes.append(tuple(int(v) for v in det))
    h, w = shape
    if not boxes:
        return slice(0, h), slice(0, w)
    x0, y0 = min(b[0] for b in boxes), min(b[1] for b in boxes)
    x1, y1 = max(b[2] for b in boxes), max(b[3] for b in boxes)
    # The frame's own shape, three times what is to be seen and at least a third of the frame.
    width = min(max(3 * (x1 - x0), 3 * (y1 - y0) * w / h, w / 3), w)
    height = width * h / w
    cx = min(max((x0 + x1) / 2, width / 2), w - width / 2)
    cy = min(max((y0 + y1) / 2, height / 2), h - height / 2)
    return (slice(int(cy - height / 2), int(cy + height / 2)), slice(int(cx - width / 2), int(cx + width / 2)))


def _outline(ax, box, colour: str, label: str, origin: tuple[int, int]) -> None:
    from matplotlib.patches import Rectangle

    x0, y0, x1, y1 = (float(v) for v in box)
    ax.add_patch(Rectangle((x0 - origin[1], y0 - origin[0]), x1 - x0, y1 - y0, fill=False, ec=colour, lw=2,
                           clip_on=True))
    ax.text(x0 - origin[1], y0 - origin[0] - 2, label, color=colour, fontsize=8, va="bottom", clip_on=True,
            bbox=dict(fc="black", alpha=0.5, pad=1, lw=0))


def _m(value) -> str:
    return "-" if value is None or not math.isfinite(float(value)) else f"{float(value):.2f} m"


def _acted_label(spec) -> str:
    """What the car acted on: the defence's distance, or the raw depth where no defence ran."""
    from racf.experiments.episode import parse_setting

    return "the raw depth acted on (no defence)" if parse_setting(spec.setting)[1] == "raw" else "the defence's distance"


def episode_outcome(log: pd.DataFrame, target: Target = SIGN) -> tuple[float, str] | None:
    """When and how the episode ended for the car: its first contact, else (following a car) its
    closest approach without one, else where it came to rest after braking (before or past the
    line), else None."""
    t = log["t"].to_numpy(float)
    if "collision_with" in log:
        hit = np.flatnonzero(log["collision_with"].fillna("").astype(str).to_numpy() != "")
        if hit.size:
            return float(t[hit[0]]), f"collision with {log['collision_with'].iloc[hit[0]]}"
    if target is LEAD and np.isfinite(_col(log, target.truth)).any():
        closest = int(np.nanargmin(_col(log, target.truth)))
        return float(t[closest]), f"no contact: closest {_m(log[target.truth].iloc[closest])} from the camera"
    brake = np.flatnonzero(_flag(log, "brake"))
    speed = _col(log, "speed")
    if brake.size:
        rest = np.flatnonzero((np.arange(len(log)) >= brake[0]) & (np.abs(speed) < 0.02))
        if rest.size:
            line = _col(log, "dist_to_stop_line")[rest[0]]
            where = "" if target is not SIGN or not math.isfinite(line) else (
                f", {line:.2f} m before the line" if line >= 0 else f", {-line:.2f} m past the line")
            return float(t[rest[0]]), f"the car at rest{where}"
    passed = np.flatnonzero(_col(log, "dist_to_stop_line") < 0) if target is SIGN else np.array([], int)
    if passed.size:
        return float(t[passed[0]]), "the car passes the line without stopping"
    return None


def gaps_caption(log: pd.DataFrame, target: Target, in_view: np.ndarray, names: dict[str, str]) -> str:
    """Where a line breaks while the target is in view, and why: its source gave no distance then."""
    dt = float(np.median(np.diff(log["t"].to_numpy(float)))) if len(log) > 1 else 0.0
    why = {target.meas: "no detection held the target", target.lidar: "no LiDAR cluster was tracked on it",
           target.fused: "it had no confirmed target: before the track is confirmed, or while it is lost"}
    parts = []
    for column, label in names.items():
        values = _col(log, column)
        if not np.isfinite(values).any():
            continue
        first, last = np.flatnonzero(np.isfinite(values))[[0, -1]]
        holes = in_view & ~np.isfinite(values) & (np.arange(len(log)) > first) & (np.arange(len(log)) < last)
        if holes.any():
            parts.append(f"{label} has none for {holes.sum() * dt:.2f} s while {target.noun} is in view "
                         f"({why[column]})")
    return ("Gaps: " + "; ".join(parts) + ".") if parts else ""


def moment_figure(spec, out: str | Path, log: pd.DataFrame | None = None, title: str | None = None) -> Path:
    """Writes the picture of ``spec``'s moment to ``out`` (PNG); returns its path. ``log`` is the
    episode's step log if it is at hand (else the episode is run for it first)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from racf.experiments.episode import run_trial

    if log is None:
        _, log = run_trial(spec)
    from racf.sim.world.manager import world_targets

    target, log = target_of(log, world_targets(spec.scenario.world(spec, spec.scenario_params)))
    moment = choose_moment(log, target)
    frame = _frame_at(spec, moment.step)
    row = frame["row"]
    rows, cols = _crop(frame, frame["rgb"].shape[:2])
    origin = (rows.start, cols.start)
    fig = plt.figure(figsize=(15, 8.6), layout="constrained")
    # The legend has a column of its own beside the distances: it never lies on the data.
    grid = fig.add_gridspec(2, 4, height_ratios=[1.0, 0.95], width_ratios=[1.0, 1.0, 1.0, 0.62])
    clean, seen, dep = (fig.add_subplot(grid[0, i]) for i in range(3))
    ser = fig.add_subplot(grid[1, :3])
    key = fig.add_subplot(grid[1, 3])
    key.axis("off")
    clean.imshow(frame["clean"][rows, cols])
    clean.set_title("what stands there (no attack)", fontsize=10)
    seen.imshow(frame["rgb"][rows, cols])
    seen.set_title("what the car's camera sees", fontsize=10)
    depth = np.where(frame["depth"] > 0, frame["depth"], np.nan)[rows, cols]
    finite = depth[np.isfinite(depth)]
    shown = dep.imshow(depth, cmap="viridis", vmin=0.0, vmax=float(np.percentile(finite, 95)) if finite.size else 3.0)
    dep.set_title("its depth camera (m; blank: no return)", fontsize=10)
    fig.colorbar(shown, ax=dep, fraction=0.046, pad=0.02)
    if frame["changed"].any():
        r, c = np.nonzero(frame["changed"])
        for ax in (seen, dep):
            _outline(ax, (c.min(), r.min(), c.max() + 1, r.max() + 1), "#ff2bd6", "the attack", origin)
    det = _detection(row)
    if det is not None:
        _outline(seen, det, "#00e0ff", "the car's detection", origin)
    for ax in (clean, seen, dep):
        ax.set_xticks([]), ax.set_yticks([])
    t = log["t"].to_numpy(float)
    in_view = _flag(log, "sign_in_view") if target is SIGN and "sign_in_view" in log else np.ones(len(log), bool)
    acted = _acted_label(spec)
    lines = ((target.truth, dict(color="black", lw=2), target.truth_label),
             (target.meas, dict(color="grey", ls="none", marker=".", ms=4), "the depth in the box"),
             (target.lidar, dict(color="#9467bd", lw=1, alpha=0.8), "the LiDAR's track"),
             (target.fused, dict(color="#1f77b4", lw=2), acted))
    for name, style, label in lines:
        values = _col(log, name)
        values = np.where(in_view, values, np.nan) if name == target.truth else values
        if np.isfinite(values).any():
            ser.plot(t, values, label=label, **style)
    attacked = _flag(log, "attack_active")
    if attacked.any():
        ser.fill_between(t, 0, 1, where=attacked, color="red", alpha=0.12, transform=ser.get_xaxis_transform(),
                         label="attack active")
    brake = np.flatnonzero(_flag(log, "brake"))
    if brake.size:
        ser.axvline(t[brake[0]], color="#d62728", lw=1.2, label="brake command")
    ser.axvline(moment.t, color="#ff7f0e", lw=2.5, ls="--", label=f"the moment above ({moment.t:.2f} s)")
    outcome = episode_outcome(log, target)
    if outcome is not None:
        ser.axvline(outcome[0], color="black", lw=2, ls=":", label=f"{outcome[1]} ({outcome[0]:.2f} s)")
    caption = gaps_caption(log, target, in_view, {target.meas: "the depth", target.lidar: "the LiDAR's track",
                                                  target.fused: acted})
    xlabel = "t (s)" + ("\n\n" + "\n".join(textwrap.wrap(caption, 150)) if caption else "")
    ser.set(xlabel=xlabel, ylabel=f"distance from the camera to {target.noun} (m)")
    ser.grid(alpha=0.3)
    key.legend(*ser.get_legend_handles_labels(), fontsize=8, loc="upper left", frameon=False)
    truth = log[target.truth].iloc[moment.step] if target.truth in log else math.nan
    numbers = (f"t = {moment.t:.2f} s, {moment.why}: {target.noun} {_m(truth)} from the camera, the depth reads "
               f"{_m(row.get(target.meas))}, {acted} {_m(row.get(target.fused))}")
    where = f"{spec.target} {spec.sign}" if spec.target != "sign" else f"sign {spec.sign}"
    fig.suptitle((title or f"{spec.setting} at {where}, {spec.speed:g} m/s, seed {spec.seed}") + "\n" + numbers,
                 fontsize=11)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
