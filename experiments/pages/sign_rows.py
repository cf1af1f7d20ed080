"""The stop sign under the supervisor (issue 78): racf-4's strong patch and racf-5's stale-map rows, ODCA
and the vote each alone and supervised on the same episodes (the sweeps ``sign-supervisor*.toml``).

Its data is the ``sign-supervisor`` stored result, made from the sweeps' folders by::

    python -m racf.experiments.pages.sign_rows outputs/sweeps/sign-supervisor \\
        outputs/sweeps/sign-supervisor-stale outputs/sweeps/sign-supervisor-sticker --out sign-supervisor.json

Per row (the sweep, the stale map's case, the defence, supervised or not): N, the share of episodes
that kept the stop rule where a sign stands (at rest 0-0.60 m before the line), and the share with a
needless stop where none stands, each with its Wilson interval.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd

from racf.experiments.pages.results_format import emit_json, meta_lines, missing, rate
from racf.experiments.pages.sweep_episodes import current_episodes
from racf.stats import wilson_interval

__all__ = ["summarise", "sign_rows_markdown", "SIGN_ROWS_COMMAND", "main"]

SIGN_ROWS_COMMAND = ("racf sweep sign-supervisor.toml; racf sweep sign-supervisor-stale.toml; racf sweep "
                     "sign-supervisor-sticker.toml; python -m racf.experiments.pages.sign_rows "
                     "outputs/sweeps/sign-supervisor outputs/sweeps/sign-supervisor-stale "
                     "outputs/sweeps/sign-supervisor-sticker")


def _share(flags: list) -> dict:
    """k of n, the rate and its Wilson interval (None where no episode applies)."""
    n, k = len(flags), int(sum(bool(f) for f in flags))
    if not n:
        return {"k": 0, "n": 0, "rate": None, "ci": None}
    lo, hi = wilson_interval(k, n)
    return {"k": k, "n": n, "rate": k / n, "ci": [lo, hi]}


def _episodes(folder: Path) -> pd.DataFrame:
    frame, _ = current_episodes(folder)  # a part left from older code is not one of them
    frame["sweep"] = folder.name
    frame["supervised"] = frame["trial_id"].str.contains(r"\+supervisor_", regex=True)
    if "scenario_case" not in frame:
        frame["scenario_case"] = "mapped"
    return frame


def summarise(folders: list[Path]) -> dict:
    """A row per sweep, case, defence and supervision, keyed by those joined with ``|``."""
    frame = pd.concat([_episodes(Path(f)) for f in folders], ignore_index=True)
    out = {}
    for (sweep, case, estimator, supervised), group in frame.groupby(
            ["sweep", "scenario_case", "estimator", "supervised"], sort=True):
        rule = [bool(v) for v in group["stop_rule"] if v is not None and v == v]
        needless = [not bool(v) for v in group["no_needless_stop"] if v is not None and v == v]
        out["|".join([sweep, case, estimator, str(bool(supervised))])] = {
            "sweep": sweep, "case": case, "estimator": estimator, "supervised": bool(supervised), "n": len(group),
            "stop_rule": _share(rule), "needless_stop": _share(needless),
            "collisions": int(group["collision"].astype(bool).sum())}
    return {"rows": out}


def sign_rows_markdown(root: Path) -> list[str]:
    lines = ["## The stop sign under the supervisor", "",
             "racf-4's strong patch (random draws over the four signs) and racf-5's stale map (a temporary sign the "
             "map does not list, a mapped sign that is gone, a stop-sign picture on a wall, a sign moved 1 m along the "
             "lane; the 0.6 sticker up from the start on a mapped and on a temporary sign), each defence alone and "
             "supervised on the same episodes. The supervisor can only add a stop: the rows where no sign stands say "
             "whether it adds needless ones.", ""]
    path = Path(root) / "sign-supervisor.json"
    if not path.exists():
        return lines + missing("sign-supervisor", SIGN_ROWS_COMMAND)
    data = json.loads(path.read_text())
    lines += meta_lines(data["meta"]) + [
        "| sweep | case | defence | N | kept the stop rule [95 % CI] | needless stop [95 % CI] | collisions |",
        "|---|---|---|---|---|---|---|"]
    for row in data["rows"].values():
        def cell(share):
            return "—" if not share["n"] else f"{share['k']} of {share['n']} ({rate(share['rate'], share['ci'])})"
        lines.append(f"| {row['sweep']} | {row['case']} | {row['estimator']}{' + supervisor' if row['supervised'] else ''} "
                     f"| {row['n']} | {cell(row['stop_rule'])} | {cell(row['needless_stop'])} | {row['collisions']} |")
    return lines + [""]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m racf.experiments.pages.sign_rows",
                                     description="The stop sign's supervised rows from sweep folders, as JSON.")
    parser.add_argument("folders", nargs="+", type=Path, help="sweep output folders (sign-supervisor*)")
    parser.add_argument("--out", type=Path, default=None, help="write the JSON here (default: print it)")
    args = parser.parse_args(argv)
    try:
        data = summarise(args.folders)
    except (OSError, ValueError, KeyError) as err:
        print(f"sign_rows: {err}", file=sys.stderr)
        return 2
    emit_json(data, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
