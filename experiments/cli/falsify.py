"""``racf falsify`` (search a defence's worst case) and ``racf replay-case`` (rerun a counterexample)."""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

from racf.experiments.cli.common import backend_flags, fail, output_dir, plugin_flag

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    from racf.experiments.falsify.choices import OBJECTIVES, SAMPLERS

    f = sub.add_parser("falsify", help="search the attack and scenario space for a defence's worst case "
                                       "(Optuna TPE, CMA-ES, random) on the stop rule's STL robustness")
    f.add_argument("--defence", required=True, metavar="NAME", help="the defence (estimator) under test: racf list")
    f.add_argument("--attack", default="dropout_timed", metavar="A[,B]",
                   help="the attacks every episode runs, comma-separated (default dropout_timed)")
    f.add_argument("--budget", type=int, default=100, help="episodes per search (default 100)")
    f.add_argument("--sampler", nargs="+", choices=SAMPLERS, default=list(SAMPLERS),
                   help="samplers to run (default all three: random is the baseline)")
    f.add_argument("--seeds", type=int, default=10, help="search seeds per sampler, 0..N-1 (default 10)")
    f.add_argument("--batch", type=int, default=4,
                   help="trials each search asks per round (default 4); part of a study's identity")
    f.add_argument("--space", type=Path, default=None, help="the search space, TOML (default the shipped one: "
                                                            "experiments/falsify/spaces/default.toml)")
    f.add_argument("--sensor-profile", choices=("qcar2", "ideal"), default="qcar2", help="the car's sensors")
    f.add_argument("--objective", choices=OBJECTIVES, default="rule",
                   help="what the samplers minimise: rule, the stop rule's robustness (default); rule-undetected, "
                        "that minus the attack's undetected error (a slope towards attacks the defence misses); gap, "
                        "the smallest clear gap to the car ahead (lead_vehicle; below zero: contact). A violation is "
                        "the rule's robustness below zero (gap: a contact)")
    f.add_argument("--stop-at-violation", action="store_true",
                   help="end each search at its first violation (faster; the lowest robustness is then not the "
                        "budget's)")
    f.add_argument("--out", type=output_dir, default=None,
                   help="results folder (default outputs/falsify/DEFENCE-ATTACKS); a rerun resumes it")
    f.add_argument("--no-cases", action="store_true", help="do not record the distinct violations as cases")
    backend_flags(f, workers_help="parallel episodes (local processes, or a local Ray's CPUs)")
    f.add_argument("--json", action="store_true", help="print the report as one JSON object")
    plugin_flag(f)
    f.set_defaults(handler=_falsify)

    r = sub.add_parser("replay-case", help="rerun saved counterexamples (a case file or a folder of them): on the "
                                           "same code to the bit; with --defence, against another defence")
    r.add_argument("cases", nargs="*", type=Path, help="case files, or folders of them")
    r.add_argument("--suite", action="store_true",
                   help="replay racf's shipped regression suite (experiments/falsify/cases) too")
    r.add_argument("--defence", default=None, metavar="NAME",
                   help="replay the cases' scenario and attacks against this defence instead of their own")
    r.add_argument("--rerun", type=Path, default=None, metavar="FILE.rrd",
                   help="record the replay to this rerun file (one case only)")
    r.add_argument("--reseed", type=int, default=0, metavar="N",
                   help="also run each case's parameters under N other noise seeds and count the violations: "
                        "whether the failure belongs to the parameters or to one draw of the noise")
    r.add_argument("--json", action="store_true", help="print the replays as one JSON object")
    plugin_flag(r)
    r.set_defaults(handler=_replay)


def _falsify(args: argparse.Namespace) -> int:
    from racf.experiments.car.estimators import ESTIMATORS
    from racf.experiments.falsify.run import falsify, render

    if args.defence not in ESTIMATORS:
        fail("falsify", f"unknown defence {args.defence!r}; choose from {', '.join(ESTIMATORS)}")
    attacks = tuple(a for a in args.attack.split(",") if a)
    if not 1 <= args.seeds <= 1000:
        fail("falsify", f"--seeds must be in [1, 1000], got {args.seeds}")
    suffix = "" if args.objective == "rule" else f"-{args.objective}"
    out = args.out or Path("outputs/falsify") / f"{args.defence}-{'+'.join(attacks)}{suffix}"
    try:
        report = falsify(args.defence, attacks, out, budget=args.budget, samplers=tuple(args.sampler),
                         seeds=tuple(range(args.seeds)), batch=args.batch, space_path=args.space,
                         fixed={"sensor_profile": args.sensor_profile}, stop_at_violation=args.stop_at_violation,
                         backend=args.backend, workers=args.workers, address=args.address,
                         cases=not args.no_cases, objective=args.objective)
    except ValueError as err:
        fail("falsify", str(err))
    print(json.dumps(report, indent=1, allow_nan=False) if args.json else render(report))
    return 0


def _replay(args: argparse.Namespace) -> int:
    from racf.experiments.car.estimators import ESTIMATORS
    from racf.experiments.falsify.cases import load_case, replay_case, reseed_case

    if args.defence is not None and args.defence not in ESTIMATORS:
        fail("replay-case", f"unknown defence {args.defence!r}; choose from {', '.join(ESTIMATORS)}")
    from racf.experiments.falsify.cases import SUITE

    if not args.cases and not args.suite:
        fail("replay-case", "name case files or folders, or --suite for racf's shipped regression suite")
    files = []
    for path in [*args.cases, *([SUITE] if args.suite else [])]:
        if path.is_dir():
            files += sorted(path.glob("*.json"))
        elif path.exists():
            files.append(path)
        else:
            fail("replay-case", f"no case file or folder at {path}")
    if not files:
        fail("replay-case", f"no case files (*.json) in {', '.join(map(str, args.cases))}")
    if not 0 <= args.reseed <= 1000:
        fail("replay-case", f"--reseed must be in [0, 1000] other seeds, got {args.reseed}")
    if args.rerun is not None and len(files) != 1:
        fail("replay-case", f"--rerun records one case; {len(files)} given")
    try:
        cases = [load_case(f) for f in files]
    except ValueError as err:
        fail("replay-case", str(err))
    rows, broken = [], 0
    for case in cases:
        t0 = time.perf_counter()
        replay = replay_case(case, args.defence, args.rerun)
        broken += replay.identical is False
        rows.append({"case": case.name, "defence": replay.spec.estimator, "robustness_then_m": case.robustness_m,
                     "robustness_now_m": replay.robustness_m, "same_code": replay.same_code,
                     "identical": replay.identical, "verdict": "survives" if replay.survived else "violates",
                     "failure": replay.failure, "wall_s": round(time.perf_counter() - t0, 2)})
        if args.reseed:
            others = reseed_case(case, args.reseed, args.defence)
            rows[-1]["reseeded"] = {"n": len(others), "violations": sum(v < 0 for v in others),
                                    "robustness_median_m": float(statistics.median(others)),
                                    "robustness_min_m": min(others)}
        if not args.json:
            print(_replay_line(rows[-1]), flush=True)
    if args.json:
        print(json.dumps({"replays": rows}, indent=1, allow_nan=False))
    else:
        survived = sum(r["verdict"] == "survives" for r in rows)
        print(f"{len(rows)} case(s): {survived} survived, {len(rows) - survived} still violate"
              + (f"; {broken} did NOT replay to the bit on the same code" if broken else ""))
    if broken:
        print("racf replay-case: a case replayed to another robustness on the code it was found on", file=sys.stderr)
    return 1 if broken else 0


def _replay_line(row: dict) -> str:
    now = row["robustness_now_m"]
    same = {True: "identical", False: "DIFFERS", None: "other code or defence"}[row["identical"]]
    line = (f"{row['case']:<48} {row['defence']:<6} then {row['robustness_then_m']:+.4f} m  "
            f"now {now:+.4f} m  {row['verdict']:<9} ({same})")
    other = row.get("reseeded")
    if other:
        line += (f"\n{'':<48} other seeds: {other['violations']}/{other['n']} violate, median "
                 f"{other['robustness_median_m']:+.3f} m, lowest {other['robustness_min_m']:+.3f} m")
    return line
