"""``racf bench offline`` (the offline repair benchmark) and the speed benchmarks: ``bench-sim``,
``bench-loop`` and ``bench-detector``."""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

from racf.experiments.cli.common import count, fail, fmt_ci, output_dir, plugin_flag, sensor_flags

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    from racf.plugins import DETECTORS

    b = sub.add_parser("bench-sim", help="simulator steps per second and real-time factor at 50 Hz")
    b.add_argument("--steps", type=int, default=250, help="control steps per setting (default 250)")
    b.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    b.add_argument("--traffic-cars", type=int, default=0, metavar="N",
                   help="instead: time the full sensor set without and with N other cars crossing at the sign, "
                        "in alternation, and print the ratio of the real-time factors (1-4)")
    b.add_argument("--repeats", type=int, default=3, help="with --traffic-cars: timed pairs (default 3)")
    sensor_flags(b, geometry_default=None)
    b.set_defaults(handler=_bench_sim)

    ob = sub.add_parser("bench-offline", help="the offline repair benchmark: every registered estimator (raw, EKF, ODCA, "
                                      "plug-ins) beside the LiDAR reference and the forecasters (Chronos-2, SOFTS, "
                                      "NHITS, DLinear, NLinear) on both splits and presets (tables, figures, "
                                      "results.json)")
    ob.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    ob.add_argument("--out", type=output_dir, default=Path("outputs/bench"),
                    help="results folder (default outputs/bench)")
    ob.add_argument("--split", choices=("by_series", "leave_target_out", "both"), default="both",
                    help="split scheme(s) to run (default both)")
    ob.add_argument("--seed", type=int, default=0, help="training and bootstrap seed (default 0)")
    ob.add_argument("--quick", action="store_true",
                    help="a few series per split and short training (about a minute; not a result to quote)")
    ob.add_argument("--draws", type=count, default=None,
                    help="corruption draws per preset, each seeded by (drive seed, preset, draw); scores are means "
                         "over them (default 5; --quick 2)")
    ob.add_argument("--no-ablation", action="store_true",
                    help="skip the ablation (six head trainings: the losses, the two-witness gate, no kinematics)")
    ob.add_argument("--max-steps", type=count, default=None,
                    help="optimiser steps of the neuralforecast baselines (default 600; --quick 15)")
    ob.add_argument("--epochs", type=count, default=None, help="ODCA head epochs (default 800; --quick 40)")
    ob.add_argument("--json", action="store_true", help="print the results as one JSON object instead of the table")
    plugin_flag(ob)
    ob.set_defaults(handler=_bench)

    bl = sub.add_parser("bench-loop", help="closed-loop throughput: real-time factor on one core (clean, attack + "
                                           "ODCA), sweep episodes per minute with 1 / 2 workers and on Ray")
    bl.add_argument("-n", type=count, default=8, help="episodes per real-time-factor setting (default 8)")
    bl.add_argument("--rate-episodes", type=count, default=48,
                    help="episodes per throughput run, timed once the workers are up (default 48: enough that "
                         "the batch's last episode, which runs alone, does not weigh on the scaling)")
    bl.add_argument("--no-ray", action="store_true", help="skip the Ray measurement")
    bl.add_argument("--json", action="store_true", help="print one JSON object")
    sensor_flags(bl, geometry_default=None)
    bl.set_defaults(handler=_bench_loop)

    g = sub.add_parser("bench-guard", help="the speed guard: the closed loop's step cost over bare physics, in "
                                           "one run; --check fails when it is more than 15 %% above the stored one",
                       description="Times one attack + ODCA episode and the same number of bare physics steps, "
                                   "in alternation, and prints their ratio (the median over rounds). --store "
                                   "keeps it for this commit in docs/results/data/speed-guard.json; --check "
                                   "compares it with the newest stored one (make check-speed). Run it alone on "
                                   "the machine, before a change to the loop lands; not in CI.")
    g.add_argument("--rounds", type=count, default=5, help="alternating rounds (default 5)")
    g.add_argument("--check", action="store_true", help="exit 1 when the ratio is worse than stored by > 15 %%")
    g.add_argument("--store", action="store_true", help="store the ratio for this commit")
    g.add_argument("--slowdown", type=float, default=1.0, metavar="X",
                   help="make the loop X times slower on purpose (busy work after each step): shows that --check "
                        "catches a regression (default 1: none)")
    g.add_argument("--json", action="store_true", help="print one JSON object")
    g.set_defaults(handler=_bench_guard)

    bp = sub.add_parser("bench-paired", help="this checkout's closed loop against another checkout's, timed in "
                                             "alternation on one core: ms a step of each and their ratio",
                        description="Runs the same episodes in a warm worker of each checkout, pinned to one core, "
                                    "old and new in turn, and prints each round's ms a control step and the median "
                                    "ratio new / old (below 1: this checkout is faster). Make the baseline with "
                                    "`git worktree add /tmp/old <rev>`. Run it alone on the machine.")
    bp.add_argument("--baseline", required=True, metavar="DIR", help="a checkout of the code to compare against")
    bp.add_argument("--rounds", type=count, default=6, help="alternating rounds (default 6)")
    bp.add_argument("--episodes", type=count, default=6, help="episodes a round in each checkout (default 6)")
    bp.add_argument("--setting", default="attack+odca", help="the episodes' setting (default attack+odca)")
    bp.add_argument("--json", action="store_true", help="print one JSON object")
    bp.set_defaults(handler=_bench_paired)

    bd = sub.add_parser("bench-detector", help="stop-sign detectors side by side: recall and false-positive frames "
                                               "on held-out views and approach drives, time per frame on one core")
    bd.add_argument("--detector", choices=("both", *DETECTORS.names()), default="both",
                    help="which detector(s) to measure (default both, side by side)")
    bd.add_argument("--seed", type=int, default=0, help="seed of the approach drives (default 0)")
    bd.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    bd.set_defaults(handler=_bench_detector)

    bo = sub.add_parser("bench-poses", help="stop-sign detectors' recall over the poses real signs stand in: turned "
                                            "about the pole and leaned back, at the approach distances")
    bo.add_argument("--detector", choices=("both", *DETECTORS.names()), default="both",
                    help="which detector(s) to measure (default both, side by side)")
    bo.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    bo.set_defaults(handler=_bench_poses)

    br = sub.add_parser("bench-radio", help="what checking the car ahead's signed broadcast costs: Ed25519 "
                                           "verification per message on one core (p50, p99) against the 20 ms period")
    br.add_argument("--messages", type=int, default=5000, help="messages timed, one at a time (default 5000)")
    br.add_argument("--json", action="store_true", help="print one JSON object instead of a line")
    br.set_defaults(handler=_bench_radio)

    bt = sub.add_parser("bench-traffic", help="perception under cross-traffic: a car between the ego car and the "
                                              "sign, one crossing behind it, a red car in view; each paired with "
                                              "the same clean approach on the empty map")
    bt.add_argument("--seeds", type=int, default=10, help="paired approaches per case and estimator (default 10)")
    bt.add_argument("--estimator", nargs="+", default=["raw", "odca"], metavar="NAME",
                    help="estimators to run (default raw odca)")
    bt.add_argument("--case", nargs="+", default=None, metavar="CASE",
                    help="cases to run (default all: between, behind_sign, red_behind, red_car)")
    bt.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    bt.set_defaults(handler=_bench_traffic_views)


def _bench_radio(args: argparse.Namespace) -> int:
    from racf.experiments.bench.radio import time_verification

    if args.messages < 100:
        fail("bench radio", f"--messages must be at least 100 (a p99 needs them), got {args.messages}")
    out = time_verification(args.messages)
    if args.json:
        print(json.dumps(out))
    else:
        print(f"broadcast check (parse, Ed25519 verify, number and age), one core, {out['messages']} messages: "
              f"p50 {out['p50_us']:.0f} us, p99 {out['p99_us']:.0f} us, max {out['max_us']:.0f} us; p99 is "
              f"{100 * out['p99_share_of_period']:.2f} % of the {out['control_period_ms']:g} ms control period")
    return 0


def _bench_sim(args: argparse.Namespace) -> int:
    from racf.experiments.bench.sim import bench_sim

    if args.steps < 10:
        fail("bench-sim", "--steps must be >= 10")
    if args.sign_geometry is not None:
        fail("bench-sim", "--sign-geometry does not apply here: the benchmark times the default signs")
    if args.traffic_cars:
        return _bench_traffic(args)
    from racf.experiments.bench.sim import RATIO_ROW

    rows = bench_sim(steps=args.steps, sensor_profile=args.sensor_profile)
    over_floor = next(r for r in rows if r.setting == RATIO_ROW).steps_per_s
    rows = [r for r in rows if r.setting != RATIO_ROW]
    if args.json:
        print(json.dumps({**{r.setting: {"steps_per_s": round(r.steps_per_s, 1),
                                         "real_time_factor": round(r.real_time_factor, 2)} for r in rows},
                          "full_over_floor_320x240": round(over_floor, 3)}))
        return 0
    print(f"{'setting':<28}{'steps/s':>10}{'real-time factor':>18}")
    for r in rows:
        print(f"{r.setting:<28}{r.steps_per_s:>10.1f}{r.real_time_factor:>18.2f}")
    print("real-time factor = simulated seconds per wall-clock second at the 50 Hz control rate; the floor is "
          "MuJoCo's bare physics, one render and readback a frame and the A2M12's rays, each timed alone")
    print(f"full sensors 320x240 take {over_floor:.2f} x the floor's time a step, median of 3 rounds timing the two in "
          "turn (the goal: <= 1.3, or a real-time factor >= 12)")
    return 0


def _bench_traffic(args: argparse.Namespace) -> int:
    from racf.experiments.bench.sim import bench_traffic
    from racf.sim.world.traffic import MAX_TRAFFIC_CARS

    if not 1 <= args.traffic_cars <= MAX_TRAFFIC_CARS:
        fail("bench-sim", f"--traffic-cars must be in 1..{MAX_TRAFFIC_CARS}, got {args.traffic_cars}")
    if args.repeats < 1:
        fail("bench-sim", "--repeats must be >= 1")
    r = bench_traffic(args.traffic_cars, steps=args.steps, repeats=args.repeats, sensor_profile=args.sensor_profile)
    if args.json:
        print(json.dumps({"cars": r.cars, "rtf_empty": r.rtf_empty, "rtf_traffic": r.rtf_traffic, "ratio": r.ratio}))
        return 0
    print(f"full sensors 320x240, {args.steps} steps a run, {args.repeats} pairs in alternation")
    print(f"real-time factor, empty map:   {', '.join(f'{v:.2f}' for v in r.rtf_empty)}")
    print(f"real-time factor, {r.cars} other cars: {', '.join(f'{v:.2f}' for v in r.rtf_traffic)}")
    print(f"ratio (with / without), median over the pairs: {r.ratio:.3f} (a drop of {100 * (1 - r.ratio):.1f} %)")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from racf.experiments.offline.benchmark import BenchConfig, load_splits, run_benchmark
    from racf.experiments.offline.report import main_table, strict, write_report

    if not (args.dataset / "dataset.parquet").exists():
        fail("bench", f"no dataset at {args.dataset} (make one with `racf collect --out {args.dataset}`)")
    splits = ("by_series", "leave_target_out") if args.split == "both" else (args.split,)
    extra = {"draws": args.draws} if args.draws is not None else {}
    cfg = BenchConfig.from_options(quick=args.quick, max_steps=args.max_steps, epochs=args.epochs, data=args.dataset,
                                   out=args.out, splits=splits, seed=args.seed, ablation=not args.no_ablation, **extra)
    try:
        datasets = load_splits(cfg)
    except (ValueError, FileNotFoundError) as err:
        fail("bench", str(err))
    results = run_benchmark(cfg, progress=True, datasets=datasets)
    paths = write_report(results, args.out)
    if args.json:
        print(json.dumps(strict({k: v for k, v in results.items() if k != "_traces"}), allow_nan=False))
        return 0
    figures = [k for k in paths if k not in ("results", "summary") and not k.startswith("table")]
    print(main_table(results))
    clean = results["clean"]
    for split in splits:
        c = clean[split]
        print(f"ODCA on clean input ({split}): unchanged on {100 * c['unchanged_share']:.2f} % of {c['n_depth']} "
              f"steps with a depth, RMSE against its input {1000 * c['rmse_vs_input']:.2f} mm")
    print(f"wall time {results['wall_s']:.0f} s; results in {args.out} (README.md, results.json, tables/, "
          f"figures/: {len(figures)} PNGs)")
    return 0


def _bench_loop(args: argparse.Namespace) -> int:
    from racf.experiments.bench.loop import bench_loop

    if args.sign_geometry is not None:
        fail("bench-loop", "--sign-geometry does not apply here: the benchmark times the default signs")
    r = bench_loop(n_rtf=args.n, n_rate=args.rate_episodes, ray=not args.no_ray, progress=not args.json,
                   sensor_profile=args.sensor_profile)
    if args.json:
        print(json.dumps(r, allow_nan=False))
        return 0
    for key, value in r.items():
        print(f"{key:<22}{value:.2f}" if isinstance(value, float) else f"{key:<22}{value}")
    print(f"against the goals: rtf_attack_odca / 5 = {r['rtf_attack_odca'] / 5:.2f}, "
          f"scaling_efficiency / 0.9 = {r['scaling_efficiency'] / 0.9:.2f} (>= 1 meets each)")
    return 0


def _bench_guard(args: argparse.Namespace) -> int:
    from racf.experiments.bench.guard import TOLERANCE, measure_guard
    from racf.experiments.bench.guard_store import GUARD_FILE, load_guard, store_guard

    if not 1.0 <= args.slowdown <= 5.0:
        fail("bench-guard", f"--slowdown must be in [1, 5], got {args.slowdown}")
    if args.store and args.slowdown != 1.0:
        fail("bench-guard", "--store keeps a real measurement: drop --slowdown")
    stored = load_guard() if args.check else None
    if args.check and stored is None:
        fail("bench-guard", f"no stored ratio in {GUARD_FILE}: run `racf bench guard --store` on a commit first")
    result = measure_guard(rounds=args.rounds, slowdown=args.slowdown)
    out = result.to_dict()
    if stored is not None:
        out["stored"] = {"commit": stored["commit"], "ratio": stored["ratio"]}
        out["change"] = result.ratio / stored["ratio"] - 1.0
        out["passed"] = out["change"] <= TOLERANCE
    if args.store:
        out["stored_as"] = store_guard(result)
    if args.json:
        print(json.dumps(out, allow_nan=False))
    else:
        print(f"loop step {statistics.median(result.loop_step_ms):.2f} ms, bare physics step "
              f"{statistics.median(result.physics_step_ms):.3f} ms: ratio {result.ratio:.2f} "
              f"(rounds {', '.join(f'{r:.2f}' for r in result.ratios)}; {result.steps} steps a round"
              + (f", slowed x{args.slowdown:g} on purpose" if args.slowdown != 1.0 else "") + ")")
        if stored is not None:
            print(f"stored at {stored['commit']}: {stored['ratio']:.2f}; change {out['change']:+.1%} "
                  f"(allowed: +{TOLERANCE:.0%}): {'passed' if out['passed'] else 'FAILED'}")
        if args.store:
            print(f"stored in {out['stored_as']}")
    return 0 if stored is None or out["passed"] else 1


def _bench_paired(args: argparse.Namespace) -> int:
    from racf.experiments.bench.paired import bench_paired, checkout_root
    from racf.experiments.episode.spec import TrialSpec

    baseline = checkout_root(args.baseline)
    try:
        TrialSpec(args.setting, 0, 1.5, 0)
    except ValueError as err:
        fail("bench-paired", f"--setting: {err}")

    def show(r: int, old: float, new: float) -> None:
        if not args.json:
            print(f"round {r + 1}/{args.rounds}: old {old:.3f} ms, new {new:.3f} ms a step: new / old {new / old:.3f}",
                  flush=True)

    result = bench_paired(baseline, args.rounds, args.setting, args.episodes, on_round=show)
    out = result.to_dict()
    if args.json:
        print(json.dumps(out, allow_nan=False))
    else:
        print(f"{args.setting}, {args.episodes} episodes a round, {args.rounds} rounds: new / old {result.ratio:.3f} "
              f"(median; rounds {min(result.ratios):.3f}-{max(result.ratios):.3f}); real-time factor "
              f"{out['old_rtf']:.2f} -> {out['new_rtf']:.2f}")
    return 0


def _bench_traffic_views(args: argparse.Namespace) -> int:
    from racf.experiments.bench.traffic_views import CASES, OFF_M, measure_case
    from racf.experiments.car.estimators import ESTIMATORS

    cases = args.case or list(CASES)
    bad = [c for c in cases if c not in CASES]
    if bad:
        fail("bench-traffic", f"unknown case(s) {bad}; allowed: {', '.join(CASES)}")
    bad = [e for e in args.estimator if e not in ESTIMATORS]
    if bad:
        fail("bench-traffic", f"unknown estimator(s) {bad}; allowed: {', '.join(ESTIMATORS)}")
    if args.seeds < 1:
        fail("bench-traffic", "--seeds must be >= 1")
    rows = [measure_case(CASES[c], seeds=args.seeds, estimator=e) for c in cases for e in args.estimator]
    if args.json:
        print(json.dumps({"seeds": args.seeds, "off_m": OFF_M, "rows": rows}, allow_nan=False))
        return 0
    print(f"clean approaches at 1 m/s, {args.seeds} seeds per row, each run on the empty map and with the other car; "
          f"'off': share of the in-view steps more than {OFF_M} m from d_true")
    print(f"{'case':<12}{'estimator':<10}{'map':<9}{'SCR [95 % CI]':>22}{'collisions':>11}{'recall':>8}"
          f"{'depth off':>11}{'LiDAR off':>11}")
    for r in rows:
        for name in ("empty", "traffic"):
            x = r[name]
            print(f"{r['case']:<12}{r['estimator']:<10}{name:<9}{x['scr']:>8.2f} {fmt_ci(*x['scr_ci']):>13}"
                  f"{x['collisions']:>11}{x['recall']:>8.3f}{x['depth_off_share']:>11.3f}{x['lidar_off_share']:>11.3f}")
    return 0


def _bench_poses(args: argparse.Namespace) -> int:
    import json

    from tqdm import tqdm

    from racf.controllers.detectors import make_detector
    from racf.experiments.detector.pose_grid import DISTANCES_M, GRID, LEANS_DEG, TURNS_DEG, pose_recall, pose_views
    from racf.plugins import DETECTORS

    names = tuple(DETECTORS) if args.detector == "both" else (args.detector,)
    total = 4 * len(DISTANCES_M) * len(TURNS_DEG) * len(LEANS_DEG)
    views = tqdm(pose_views(), total=total, desc="pose grid", unit="view", disable=args.json)
    result = pose_recall({name: make_detector(name) for name in names}, views)
    if args.json:
        print(json.dumps(result, indent=1, allow_nan=False))
        return 0
    print(f"recall over the pose grid ({GRID}); each cell: recall [95 % CI] (N resolvable views)")
    for name in names:
        print(f"\n{name}: overall {_recall(result[name]['overall'])}")
        print(f"{'lean / turn':<12}" + "".join(f"{t:>25g}" for t in TURNS_DEG))
        for lean in LEANS_DEG:
            cells = [result[name]["by_pose"].get(f"{turn:g},{lean:g}") for turn in TURNS_DEG]
            print(f"{lean:<12g}" + "".join(f"{_recall(c):>25}" for c in cells))
    return 0


def _recall(rate: dict | None) -> str:
    return "-" if not rate or rate["recall"] is None else f"{rate['recall']:.2f} {fmt_ci(*rate['ci'])} ({rate['n']})"


def _bench_detector(args: argparse.Namespace) -> int:
    from racf.experiments.bench.detector import BUDGET_MS, FRAME_PERIOD_MS, bench_detector
    from racf.experiments.detector.dataset import DEFAULT_DATA_DIR, load_split, make_dataset
    from racf.plugins import DETECTORS

    names = tuple(DETECTORS) if args.detector == "both" else (args.detector,)
    heldout = load_split(make_dataset(root=DEFAULT_DATA_DIR, progress=not args.json), "heldout")
    try:
        results = [bench_detector(name, seed=args.seed, heldout=heldout, progress=not args.json) for name in names]
    except FileNotFoundError as err:
        fail("bench-detector", str(err))
    if args.json:
        print(json.dumps({r.detector: r.to_dict() for r in results}, allow_nan=False))
        return 0
    h = results[0].heldout
    print(f"held-out views: {h['n_frames']} frames, {h['n_positive']} with a resolvable stop sign")
    print(f"{'detector':<11}{'held-out recall':>26}{'held-out FP frames':>28}{'drive recall (0.5-2.5 m)':>32}"
          f"{'drive FP frames':>24}{'ms/frame, 1 core':>18}{'/ 33.3 ms':>11}{'/ 3 ms':>8}")
    for r in results:
        h = r.heldout
        print(f"{r.detector:<11}{h['recall']:>10.4f} {fmt_ci(*h['recall_ci']):>15}"
              f"{h['n_fp']:>6}/{h['n_frames']} = {100 * h['fp_rate']:.2f} %"
              f"{r.recall:>14.4f} {fmt_ci(*r.recall_ci):>15} N={r.n_positive:<4}"
              f"{r.n_fp_frames:>6}/{r.n_frames} = {100 * r.fp_rate:.2f} %"
              f"{r.ms_per_frame_one_core:>14.2f}{r.ms_per_frame_one_core / FRAME_PERIOD_MS:>11.3f}"
              f"{r.ms_per_frame_one_core / BUDGET_MS:>8.2f}")
    print("goals for the learned detector: held-out recall >= 0.99, false-positive frames <= 0.1 %, "
          "time / 3 ms <= 1")
    kinds = list(results[0].heldout["by_kind"])
    bands = list(results[0].heldout["by_band"])
    print("held-out recall by kind of view and by the sign's distance [95 % CI] (N):")
    for r in results:
        cells = [f"{name} {c['recall']:.3f} {fmt_ci(*c['recall_ci'])} ({c['n_positive']})"
                 for name, c in (*((k, r.heldout["by_kind"][k]) for k in kinds), *((b, r.heldout["by_band"][b]) for b in bands))
                 if c["recall"] is not None]
        print(f"  {r.detector:<10} " + "; ".join(cells))
    print("false-positive frames with plain red squares pasted into views with no stop sign:")
    for r in results:
        q = r.red_squares
        print(f"  {r.detector:<10} {q['n_fp']}/{q['n_frames']} = {100 * q['fp_rate']:.2f} % {fmt_ci(*q['fp_rate_ci'])}")
    for r in results:
        print(f"{r.detector}: mean confidence with a share of the sign's box occluded:")
        for side, row in r.occlusion_confidence.items():
            print(f"  from the {side:<5}" + "".join(f"  {q:.1f}: {c:.2f}" for q, c in row.items()))
    return 0
