"""``racf bench`` (the offline repair benchmark) and the speed benchmarks: ``bench-sim``,
``bench-loop`` and ``bench-detector``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from experiments.cli.common import count, fail, fmt_ci, sensor_flags

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    b = sub.add_parser("bench-sim", help="simulator steps per second and real-time factor at 50 Hz")
    b.add_argument("--steps", type=int, default=250, help="control steps per setting (default 250)")
    b.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    sensor_flags(b, geometry_default=None)
    b.set_defaults(handler=_bench_sim)

    ob = sub.add_parser("bench", help="the offline repair benchmark: raw, LiDAR, EKF, Chronos-2, SOFTS, NHITS, "
                                      "DLinear, NLinear and ODCA on both splits and presets (tables, figures, "
                                      "results.json)")
    ob.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    ob.add_argument("--out", type=Path, default=Path("outputs/bench"), help="results folder (default outputs/bench)")
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

    bd = sub.add_parser("bench-detector", help="stop-sign detector recall and false-positive frames on rendered drives")
    bd.add_argument("--seed", type=int, default=0)
    bd.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    bd.set_defaults(handler=_bench_detector)


def _bench_sim(args: argparse.Namespace) -> int:
    from experiments.bench.sim import bench_sim

    if args.steps < 10:
        fail("bench-sim", "--steps must be >= 10")
    if args.sign_geometry is not None:
        fail("bench-sim", "--sign-geometry does not apply here: the benchmark times the default signs")
    rows = bench_sim(steps=args.steps, sensor_profile=args.sensor_profile)
    if args.json:
        print(json.dumps({r.setting: {"steps_per_s": round(r.steps_per_s, 1),
                                      "real_time_factor": round(r.real_time_factor, 2)} for r in rows}))
        return 0
    print(f"{'setting':<28}{'steps/s':>10}{'real-time factor':>18}")
    for r in rows:
        print(f"{r.setting:<28}{r.steps_per_s:>10.1f}{r.real_time_factor:>18.2f}")
    print("real-time factor = simulated seconds per wall-clock second at the 50 Hz control rate")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from experiments.offline.benchmark import BenchConfig, load_splits, run_benchmark
    from experiments.offline.report import main_table, strict, write_report

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
    from experiments.bench.loop import bench_loop

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


def _bench_detector(args: argparse.Namespace) -> int:
    from experiments.bench.detector import bench_detector

    r = bench_detector(seed=args.seed, progress=not args.json)
    if args.json:
        print(json.dumps(r.to_dict()))
        return 0
    print(f"frames {r.n_frames}, ms per frame {r.ms_per_frame:.2f}")
    print(f"recall (signs 0.5-2.5 m, N = {r.n_positive}): {r.recall:.3f} {fmt_ci(*r.recall_ci)}  "
          + "  ".join(f"sign {s}: {v:.3f}" for s, v in r.recall_by_sign.items()))
    print(f"false-positive frames: {r.n_fp_frames} / {r.n_frames} = {r.fp_rate:.4f} "
          f"{fmt_ci(*r.fp_rate_ci, digits=4)}")
    print("mean confidence with a share of the sign's box occluded:")
    for side, row in r.occlusion_confidence.items():
        print(f"  from the {side:<5}" + "".join(f"  {q:.1f}: {c:.2f}" for q, c in row.items()))
    return 0
