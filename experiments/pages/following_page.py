"""The following results page (``docs/results/following.md``): the car ahead and its attacks.

Its data is the ``following`` stored result, made from the sweeps ``following.toml``,
``following-frustum.toml`` and ``following-hide.toml`` (their episodes' rows, ``parts/*.parquet``) by::

    python -m racf.experiments.pages.following_page outputs/sweeps/following outputs/sweeps/following-frustum \
        outputs/sweeps/following-hide --out following.json

and stored with ``results_store``; the phantom car ahead's table is the ``following-phantom`` stored
result, made the same way from the sweep ``following-phantom.toml``, and the existence check's
section reads the defences' ``racf-6`` cards (``scorecard-racf-6``, ``RACF6_COMMAND``). Per attack and defence: N, the collision-free rate with its
Wilson interval, the smallest time-to-collision (median and bootstrap interval), the share of
episodes with any time under the minimum headway, hard brakes, and the collision-free rate per
lead profile.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd

from racf.experiments.scorecard.card_format import current_card
from racf.experiments.pages.results_format import emit_json, meta_lines, missing, page_head, rate
from racf.experiments.pages.sweep_episodes import current_episodes
from racf.stats import median_ci, wilson_interval

__all__ = ["summarise", "following_markdown", "FOLLOWING_COMMAND", "main"]

ADAPTIVE_COMMAND = ("racf sweep following-adaptive.toml; python -m racf.experiments.pages.following_page "
                    "outputs/sweeps/following-adaptive")
PHANTOM_COMMAND = ("racf sweep following-phantom.toml; python -m racf.experiments.pages.following_page "
                   "outputs/sweeps/following-phantom")
#: The battery of the car ahead, every built-in defence that follows a moving target carded on it.
RACF6_COMMAND = "racf scorecard --defence raw odca ekf chronos vote --battery racf-6 --json"
FOLLOWING_COMMAND = ("racf sweep following.toml; racf sweep following-frustum.toml; racf sweep following-hide.toml; "
                     "python -m racf.experiments.pages.following_page outputs/sweeps/following "
                     "outputs/sweeps/following-frustum outputs/sweeps/following-hide")
#: How an attack is named in the table.
ATTACK_LABELS = {"clean": "none", "clean+lead_patch": "lead patch (depth read 1 m far)",
                 "clean+lead_frustum": "frustum spoof (LiDAR returns 1 m away)",
                 "clean+lead_frustum[depth]": "frustum spoof, depth moved too",
                 "clean+lead_frustum[adaptive]": "adaptive frustum spoof: depth, LiDAR and picture moved away at "
                                                 "0.5 m/s up to 2 m",
                 "clean+lead_hide": "the lead hidden from camera and LiDAR",
                 "clean+lead_phantom": "a phantom car 0.5 m ahead (camera only)"}


def _rows(folder: Path) -> pd.DataFrame:
    frame, specs = current_episodes(folder)  # a part left from older code is not one of them
    attack = frame["setting"].str.replace(r"\+[a-z_0-9]+$", "", regex=True).where(frame["estimator"] != "raw",
                                                                                 frame["setting"])
    # The frustum spoof that moves the depth too is its own row, and the one that moves the picture too.
    frame["attack"] = attack + frame["trial_id"].map(
        lambda i: _frustum_kind(specs[i].attack_params.get("lead_frustum", {})) if i in specs else "")
    # A defence run with options is its own row: ``vote (inner=ekf)``; one under the supervisor too.
    frame["estimator"] = [_label(e, specs[i].estimator_options if i in specs else {})
                          + (" + supervisor" if i in specs and specs[i].supervisor else "")
                          for e, i in zip(frame["estimator"], frame["trial_id"])]
    return frame


def _frustum_kind(params: dict) -> str:
    return "[adaptive]" if params.get("scale_box") else "[depth]" if params.get("depth") else ""


def _label(estimator: str, options: dict) -> str:
    return estimator + (f" ({', '.join(f'{k}={v}' for k, v in sorted(options.items()))})" if options else "")


def _share(flags) -> dict:
    k, n = int(sum(bool(f) for f in flags)), len(flags)
    lo, hi = wilson_interval(k, n)
    return {"k": k, "n": n, "rate": (k / n if n else None), "ci": [lo, hi]}


def _median(group: pd.DataFrame, column: str) -> dict:
    """A column's median with its bootstrap interval (over the episodes that have it)."""
    values = group[column].to_numpy(float)
    median, ci = median_ci(values[~pd.isna(values)])
    return {"median": median, "ci": ci, "n": int((~pd.isna(values)).sum())}


def summarise(folders: list[Path], by: tuple[str, ...] = ()) -> dict:
    """The following table's data from the sweeps' folders: a row per attack and defence, and per value of
    each result column in ``by`` (``scenario_broadcast``: the lead broadcasting or not), its key those
    values joined by ``|``."""
    frame = pd.concat([_rows(Path(f)) for f in folders], ignore_index=True)
    missing_columns = [c for c in by if c not in frame]
    if missing_columns:
        raise ValueError(f"the episodes have no column(s) {missing_columns} to group by")
    out = {}
    for keys, group in frame.groupby(["attack", "estimator", *by], sort=True):
        attack, estimator, *values = keys
        ttc = group["min_ttc_s"].to_numpy(float)
        median, ci = median_ci(ttc[~pd.isna(ttc)])
        out["|".join([attack, estimator, *map(str, values)])] = {
            "attack": attack, "estimator": estimator, **dict(zip(by, map(str, values))), "n": len(group),
            "collision_free": _share(group["no_lead_collision"].tolist()),
            "min_ttc_median_s": median, "min_ttc_ci": ci,
            "headway_violated": _share((group["headway_violation_s"] > 0).tolist()),
            "hard_brakes_median": float(group["hard_brakes"].median()),
            **({"needless_hard_brake": _share((group["needless_hard_brakes"] > 0).tolist())}
               if "needless_hard_brakes" in group else {}),
            **{f"{name}_median": _median(group, name) for name in ("mean_time_gap_s", "finish_s") if name in group},
            **(_foreign(group) if "bc_injected" in group and group["bc_injected"].sum() > 0 else {}),
            "by_profile": {p: _share(g["no_lead_collision"].tolist())
                           for p, g in group.groupby("scenario_profile", sort=True)}}
    return {"rows": out}


def _foreign(group: pd.DataFrame) -> dict:
    """The forged and replayed broadcast messages: how many an attacker sent, how many the car refused,
    and the share of episodes where it refused them all."""
    sent = group["bc_injected"].to_numpy(int)
    return {"bc_injected": int(sent.sum()), "bc_refused": int(group["bc_refused"].sum()),
            "foreign_refused": _share((group["bc_refused"] >= group["bc_injected"])[sent > 0].tolist())}


def following_markdown(root: Path) -> str:
    lines = page_head(
        "Following the car ahead",
        "The `lead_vehicle` scenario: a second QCar 2 drives the car's lane on sign 1's approach, in each of "
        "its four profiles (cruise, slow down, hard brake at 3 m/s^2, stop and go), braking at 3 s; the car "
        "follows it with its vehicle segmenter, the LiDAR's track and the size witness, a 1 s time-headway "
        "policy and an emergency brake on time-to-collision. The attacks act from 2 s for 6 s. "
        "[The tutorial](../tutorials/following.md) says how it works.")
    path = Path(root) / "following.json"
    if not path.exists():
        return "\n".join(lines + missing("following", FOLLOWING_COMMAND) + _sections(Path(root)) + [""])
    data = json.loads(path.read_text())
    lines += meta_lines(data["meta"])
    lines += ["| attack | defence | N | collision-free [95 % CI] | min TTC s, median [95 % CI] | "
              "any time under 0.5 s headway [95 % CI] | hard brakes, median |", "|---|---|---|---|---|---|---|"]
    rows = dict(sorted(data["rows"].items(), key=lambda kv: _order(kv[1])))
    for r in rows.values():
        cf, hw, ttc = r["collision_free"], r["headway_violated"], _ttc(r)
        lines.append(f"| {ATTACK_LABELS.get(r['attack'], r['attack'])} | {r['estimator']} | {r['n']} | "
                     f"{rate(cf['rate'], cf['ci'])} | {ttc} | {rate(hw['rate'], hw['ci'])} | "
                     f"{r['hard_brakes_median']:g} |")
    profiles = sorted({p for r in rows.values() for p in r["by_profile"]})
    lines += ["", "Collision-free by the lead's profile (each cell: k / N):", "",
              "| attack | defence | " + " | ".join(profiles) + " |", "|---|---|" + "---|" * len(profiles)]
    for r in rows.values():
        cells = [f"{r['by_profile'][p]['k']} / {r['by_profile'][p]['n']}" if p in r["by_profile"] else "—"
                 for p in profiles]
        lines.append(f"| {ATTACK_LABELS.get(r['attack'], r['attack'])} | {r['estimator']} | " + " | ".join(cells) + " |")
    lines += ["", "What it shows: on clean runs every defence follows every profile without a touch. The patch "
              "reading the lead's depth 1 m far from before it brakes takes raw depth, the EKF and Chronos-only "
              "into it; ODCA's gate outvotes the depth with the LiDAR's track, the size witness and its kinematic "
              "branch on the closing speed. Moving the LiDAR's returns alone harms no one (raw depth does not read "
              "the LiDAR; the defences outvote it). Moving them with the depth, so that the two range sensors agree, "
              "is the harder case: ODCA holds in three profiles and loses half the hard brakes, where only the size "
              "witness and the carried closing speed still disagree with the two. Hiding the lead from every sensor "
              "leaves no witness at all: every defence drives into it in most episodes, and none can be asked to do "
              "better without a sensor that still sees it."]
    return "\n".join(lines + _sections(Path(root)) + [""])


def _stored(root: Path, name: str, command: str) -> tuple[dict | None, list[str]]:
    """A section's stored result and its provenance lines, or None and what to run to make it."""
    path = root / f"{name}.json"
    if not path.exists():
        return None, missing(name, command)
    data = json.loads(path.read_text())
    return data, meta_lines(data["meta"])


def _ttc(r: dict) -> str:
    return "—" if r["min_ttc_median_s"] is None else rate(r["min_ttc_median_s"], r["min_ttc_ci"])


def _sections(root: Path) -> list[str]:
    return _adaptive_lines(root) + _phantom_lines(root) + _existence_lines(root)


def _adaptive_lines(root: Path) -> list[str]:
    """The adaptive attack's section, from the ``following-adaptive`` stored result."""
    lines = ["", "## The adaptive attack: every witness moved", "",
             "The frustum spoof that knows ODCA's witnesses (`lead_frustum` with `depth`, `scale_box` and "
             "`rate_mps`): from 2 s the lead's LiDAR returns, its depth and its picture (drawn as small as the car "
             "would look there) move away together, growing at 0.5 m/s up to 2 m, as a lead that pulls away would. "
             "The depth, the LiDAR, the size and the relative motion then agree with each other and not with the "
             "world; only a witness outside the car's sensors could tell.", ""]
    data, provenance = _stored(root, "following-adaptive", ADAPTIVE_COMMAND)
    lines += provenance
    if data is None:
        return lines
    lines += ["| attack | defence | N | collision-free [95 % CI] | min TTC s, median [95 % CI] | hard brakes, median |",
              "|---|---|---|---|---|---|"]
    for r in sorted(data["rows"].values(), key=_order):
        cf = r["collision_free"]
        lines.append(f"| {ATTACK_LABELS.get(r['attack'], r['attack'])} | {r['estimator']} | {r['n']} | "
                     f"{rate(cf['rate'], cf['ci'])} | {_ttc(r)} | {r['hard_brakes_median']:g} |")
    return lines + ["", "What it shows: this is the attack no defence built on the car's own sensors can answer. "
                    "ODCA's gate repairs the depth when its witnesses disagree; here none does, and the relative "
                    "motion, grown as smoothly as a lead that speeds up, gives its kinematic branch nothing to "
                    "outvote. The bound it sets: a car that trusts only its own sensors can be led into the car "
                    "ahead by an attacker who moves all of them. What would answer it is a witness the attacker "
                    "does not reach (a radar's Doppler, a second camera, the lead's own broadcast speed), which "
                    "the QCar 2 does not carry."]


def _phantom_lines(root: Path) -> list[str]:
    """The phantom car ahead's section, from the ``following-phantom`` stored result."""
    lines = ["", "## A phantom car ahead", "",
             "From 2 s for 6 s the camera sees a QCar 2's rear 0.5 m ahead in the lane (a picture: drawn from the "
             "real lead's, Nassi et al., CCS 2020), while the depth and the LiDAR see what is really there. A hard "
             "brake is needless when it begins while the real lead asks for none: its time-to-collision over 3 s "
             "(or not closing) and the headway at least 0.5 s.", ""]
    data, provenance = _stored(root, "following-phantom", PHANTOM_COMMAND)
    lines += provenance
    if data is None:
        return lines
    lines += ["| attack | defence | N | any needless hard brake [95 % CI] | collision-free [95 % CI] | "
              "hard brakes, median |", "|---|---|---|---|---|---|"]
    for r in sorted(data["rows"].values(), key=lambda r: (r["attack"] != "clean", _order(r))):
        needless, cf = r["needless_hard_brake"], r["collision_free"]
        lines.append(f"| {ATTACK_LABELS.get(r['attack'], r['attack'])} | {r['estimator']} | {r['n']} | "
                     f"{rate(needless['rate'], needless['ci'])} | {rate(cf['rate'], cf['ci'])} | "
                     f"{r['hard_brakes_median']:g} |")
    return lines + ["", "Why ODCA can fare worst, as single episodes show it: its gate takes the size witness as "
                    "one-sided. An occluder or a sticker can only shrink a box, so a depth or a LiDAR beyond the box's "
                    "distance is vetoed; a phantom's box is bigger than the car's, and the gate then vetoes the honest "
                    "depth and follows the picture. None of these defences asks whether anything stands where the box "
                    "says; the existence vote does (next section)."]


#: The vote with the car ahead's existence check on, carded on racf-6 where that was its default.
LEAD_CHECK_RESULT = "racf-6-vote-lead-check"


def _existence_lines(root: Path) -> list[str]:
    """The existence check's section: the vote with the check on (``racf-6-vote-lead-check``) beside each
    defence's ``racf-6`` card (``scorecard-racf-6``), clean, under the phantom and under the frustum
    spoof that moves both range sensors."""
    lines = ["", "## The existence check of the car ahead", "",
             "The car checks whether the box ahead is a car or a picture of one (`racf.controllers.lead_existence`: "
             "something upright must stand on the lane at the box's distance; [the tutorial](../tutorials/following.md) "
             "says how it decides which of the box and the depth lies). The existence vote acts on it with "
             "`--estimator-option vote.lead_check=true`: while the box is taken for a picture it follows what stands "
             "there. Battery `racf-6` rates the defences on the same episodes as the tables above "
             "([the leaderboard](leaderboard.md) has every row). Collision-free and any needless hard brake, "
             "[95 % CI]:", ""]
    cards, metas = [], []
    for name, label in ((LEAD_CHECK_RESULT, "vote (lead_check=true)"), ("scorecard-racf-6", None)):
        path = root / f"{name}.json"
        if not path.exists():
            lines += missing(name, RACF6_COMMAND if label is None else RACF6_COMMAND.replace(
                "--defence raw odca ekf chronos vote", "--defence vote --estimator-option vote.lead_check=true"))
            continue
        data = json.loads(path.read_text())
        metas.append((name, data["meta"]))
        cards += [(label or c["defence"], current_card(c)) for c in data["cards"]]
    if not cards:
        return lines
    for name, meta in metas:
        lines += [f"`{name}`:"] + meta_lines(meta)
    keys = ("following_clean", "following_phantom", "following_frustum_depth", "following_patch")
    lines += ["| defence | " + " | ".join(k.removeprefix("following_").replace("_", " ") for k in keys) + " |",
              "|---|" + "---|" * len(keys)]
    for label, card in sorted(cards, key=lambda lc: _order({"attack": "", "estimator": lc[0]})):
        cells = []
        for key in keys:
            r = card["closed_loop"].get(key)
            measures = {m["measure"]: m for m in (r or {}).get("headline", [])}
            cells.append("—" if r is None else "; ".join(rate(measures[name]["value"], measures[name]["ci"])
                                                         for name in ("collision-free", "needless hard brake")))
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    n = {m["n"] for _, card in cards for k in keys if k in card["closed_loop"]
         for m in card["closed_loop"][k]["headline"]}
    lines += ["", f"N per cell: {', '.join(str(v) for v in sorted(n))} (15 seeds x the lead's four profiles). Each "
              "cell: collision-free; any needless hard brake.", "",
              "What it shows: with the check on, the vote no longer drives into the lead under the phantom and brakes "
              "for it less often than ODCA, but the patch and the frustum spoof with the depth then cost it collisions "
              "that ODCA alone avoids, which is why the check is off by default. The EKF, which brakes least for the "
              "phantom, follows the attacks on the range sensors into the lead. No defence here holds both."]
    return lines


#: The table's order: attacks by strength, raw first then the defences.
_ATTACKS = ("clean", "clean+lead_patch", "clean+lead_frustum", "clean+lead_frustum[depth]",
            "clean+lead_frustum[adaptive]", "clean+lead_hide",
            "clean+lead_phantom")
_DEFENCES = ("raw", "odca", "ekf", "chronos", "vote")


def _order(row: dict) -> tuple:
    a, e = row["attack"], row["estimator"]
    return (_ATTACKS.index(a) if a in _ATTACKS else len(_ATTACKS), a,
            _DEFENCES.index(e) if e in _DEFENCES else len(_DEFENCES), e)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m racf.experiments.pages.following_page",
                                     description="The following table's data from sweep folders, as JSON.")
    parser.add_argument("folders", nargs="+", type=Path, help="sweep output folders (following, following-frustum)")
    parser.add_argument("--out", type=Path, default=None, help="write the JSON here (default: print it)")
    parser.add_argument("--by", nargs="*", default=[], metavar="COLUMN",
                        help="also a row per value of these result columns (e.g. scenario_broadcast)")
    args = parser.parse_args(argv)
    try:
        data = summarise(args.folders, tuple(args.by))
    except (OSError, ValueError) as err:
        print(f"following_page: {err}", file=sys.stderr)
        return 2
    emit_json(data, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
