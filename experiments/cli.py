"""The ``racf`` command line."""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
from pathlib import Path

__all__ = ["main"]


def _sign(value: str) -> int:
    try:
        sign = int(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"sign must be an integer 0..3, got {value!r}") from None
    if sign not in range(4):
        raise argparse.ArgumentTypeError(f"sign must be 0, 1, 2 or 3, got {sign}")
    return sign


def _positive(value: str) -> float:
    v = float(value)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {value}")
    return v


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="racf", description="RACF testbed: QCar 2 simulation, attacks and ODCA.")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("snapshot", help="top view of the map and the car's camera, depth and LiDAR at a pose (PNGs)")
    s.add_argument("--sign", type=_sign, default=2, help="stop sign whose approach the car stands on (0-3, default 2)")
    s.add_argument("--run-up", type=_positive, default=1.2, help="front bumper to stop line, m (default 1.2)")
    s.add_argument("--width", type=int, default=320, help="camera width px (default 320)")
    s.add_argument("--height", type=int, default=240, help="camera height px (default 240)")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--out", type=Path, default=Path("outputs/snapshot"), help="output folder")

    b = sub.add_parser("bench-sim", help="simulator steps per second and real-time factor at 50 Hz")
    b.add_argument("--steps", type=int, default=250, help="control steps per setting (default 250)")
    b.add_argument("--json", action="store_true", help="print one JSON object instead of a table")

    d = sub.add_parser("demo", help="the story at one stop sign: clean, patch attack, attack + ODCA; a table, "
                                     "three rerun recordings and a PNG of the distance traces")
    d.add_argument("--sign", type=_sign, default=1, help="stop sign 0-3 (default 1)")
    d.add_argument("--speed", type=_speed, default=1.5, help="cruise speed m/s, 0.1-3.0 (default 1.5)")
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--out", type=Path, default=Path("outputs/demo"), help="output folder")
    t = sub.add_parser("trial", help="one closed-loop stop-sign trial: per-step log (Parquet) and result row")
    _episode_flags(t)
    t.add_argument("--sign", type=_sign, default=2, help="stop sign 0-3, or crate 0-1 with --target obstacle (default 2)")
    t.add_argument("--target", choices=("sign", "obstacle", "drive"), default="sign",
                   help="approach a stop sign (default) or an obstacle crate, or a random 20-60 s drive (--sign 0)")
    t.add_argument("--speed", type=_speed, default=1.0, help="cruise speed m/s, 0.1-3.0 (default 1.0)")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--out", type=Path, default=Path("outputs/trial"), help="output folder")
    t.add_argument("--rerun", type=Path, default=None, metavar="PATH",
                   help="also record the episode to a rerun file (.rrd; open it with `racf view PATH`)")

    sw = sub.add_parser("sweep", help="a Monte Carlo attack sweep from a TOML spec or flags (grid or random draws) "
                                      "on a local process pool or Ray; resumes; summary and SCR plots")
    sw.add_argument("spec", nargs="?", type=Path, default=None,
                    help="the sweep spec (TOML); shipped: smoke.toml, attack-types.toml, strong-1000.toml. "
                         "Without one, the flags below make the sweep")
    sw.add_argument("--out", type=Path, default=None, help="results folder (default outputs/sweeps/<spec name>)")
    sw.add_argument("--backend", choices=("local", "ray"), default="local",
                    help="local spawned processes (default) or Ray")
    sw.add_argument("--address", default=None, help="with --backend ray: the cluster to join (default: start a "
                                                   "local Ray)")
    sw.add_argument("--workers", type=_count, default=min(2, os.cpu_count() or 1),
                    help="parallel episodes (local processes, or a local Ray's CPUs)")
    sw.add_argument("--json", action="store_true", help='print {"n", "done", "reused", "wall_s", "scr"} as JSON')
    sw.add_argument("--report", type=Path, default=None, metavar="DIR",
                    help="redraw the summary and plots of a stored sweep, running nothing")
    fl = sw.add_argument_group("a sweep from flags (alone, or replacing the spec's fields)")
    fl.add_argument("--name", default=None, help="the sweep's name (default: the spec's, or one made from its content)")
    fl.add_argument("--mode", choices=("grid", "random"), default=None,
                    help="grid: every combination, --repeats seeds each; random: --n draws")
    fl.add_argument("--n", type=_count, default=None, help="random mode: draws (each run with every estimator)")
    fl.add_argument("--repeats", type=_count, default=None, help="grid mode: seeds per cell")
    fl.add_argument("--seed", type=int, default=None, help="the sweep's seed")
    fl.add_argument("--log-steps", action="store_true", default=None, help="also keep every episode's per-step log")
    fl.add_argument("--attack", nargs="+", default=None, metavar="A",
                    help="'none', an attack or '+'-joined attacks: patch, depth_blackout, depth_bias, "
                         "confidence_degradation, lidar_dropout, lidar_spoof")
    fl.add_argument("--estimator", nargs="+", default=None, metavar="E", help="raw, odca, ekf, chronos")
    for flag, what in (("--rho", "patch coverage in [0, 1]"), ("--t-atk", "attack duration s"),
                       ("--speed", "cruise speed m/s")):
        fl.add_argument(flag, nargs="+", type=float, default=None, metavar="X",
                        help=f"{what}: values (grid) or LOW HIGH (random)")
    fl.add_argument("--sign", nargs="+", type=int, default=None, metavar="K", help="stop signs 0-3")

    vw = sub.add_parser("view", help="open a rerun recording (.rrd) in the rerun viewer")
    vw.add_argument("path", type=Path, help="the .rrd file (racf demo, racf trial --rerun)")

    ts = sub.add_parser("trials", help="a batch of trials over the four signs and speeds 1.0/1.5/2.0 m/s: SCR, latency")
    _episode_flags(ts)
    ts.add_argument("--table", action="store_true",
                    help="the paper's table: every setting of TABLE_SETTINGS (clean, clean+odca, attack, attack+odca, "
                         "attack+ekf, attack+chronos, attack+lidar_spoof+odca), N per setting")
    ts.add_argument("-n", type=_count, default=30, help="number of trials (default 30; 12 cover every sign x speed)")
    ts.add_argument("--seed", type=int, default=0, help="seed of the first trial; trial i uses seed + i")
    ts.add_argument("--workers", type=_count, default=min(2, os.cpu_count() or 1), help="parallel processes")
    ts.add_argument("--out", type=Path, default=None,
                    help="output folder (default outputs/trials/<setting>, outputs/table with --table); finished "
                         "trials there are reused (their ids hash the spec, configs and code version)")
    ts.add_argument("--json", action="store_true", help="print one JSON summary object instead of tables")
    ts.add_argument("--rerun", action="store_true",
                    help="also record every trial that runs to rerun: <out>/trials/<trial_id>.rrd (`racf view`)")

    st = sub.add_parser("attack-study", help="no-defence patch attack tables: persistence, coverage, strong regime")
    st.add_argument("studies", nargs="*", default=None, metavar="STUDY",
                    help="persistence, coverage and/or strong (default all three)")
    st.add_argument("-n", type=_count, default=24, help="trials per table row (default 24; the strong row uses max(n, 30))")
    st.add_argument("--seed", type=int, default=0)
    st.add_argument("--workers", type=_count, default=min(2, os.cpu_count() or 1), help="parallel processes")
    st.add_argument("--out", type=Path, default=Path("outputs/attack_study"), help="output folder (trials are reused)")
    st.add_argument("--json", action="store_true", help="print one JSON object instead of tables")

    co = sub.add_parser("collect", help="record the multi-sensor dataset of drives (Parquet, splits, card); resumes")
    co.add_argument("--out", type=Path, default=Path("data/qcar2"), help="dataset folder (default data/qcar2)")
    co.add_argument("--drives", type=_count, default=None,
                    help="drives of 20-60 s, each meeting >= 2 targets (default 36: > 67,821 samples)")
    co.add_argument("--seed", type=int, default=0, help="collection seed (drive seeds and the splits)")
    co.add_argument("--workers", type=_count, default=min(2, os.cpu_count() or 1), help="parallel processes")
    co.add_argument("--summary", action="store_true", help="print the summary as one JSON object")

    pp = sub.add_parser("pretrain-prior", help="pretrain the small Chronos-2 prior on synthetic series (writes a model card)")
    pp.add_argument("--out", type=Path, default=Path("outputs/chronos2-prior"),
                    help="checkpoint folder (default outputs/chronos2-prior; name assets/checkpoints/chronos2-racf-tiny "
                         "to replace the shipped prior)")
    pp.add_argument("--steps", type=_count, default=3000, help="training steps (default 3000)")
    pp.add_argument("--series", type=_count, default=6000, help="synthetic training series (default 6000)")
    pp.add_argument("--seed", type=int, default=0)
    pp.add_argument("--dataset", type=Path, default=Path("data/qcar2"),
                    help="dataset whose test-split d_clean series are scored too, if it exists")

    tr = sub.add_parser("train", help="train the ODCA delta head, alignment and gate on the dataset's train split")
    tr.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    tr.add_argument("--split", choices=("by_series", "leave_target_out"), default="by_series",
                    help="split scheme to train on and score (default by_series)")
    tr.add_argument("--out", type=Path, default=Path("outputs/odca-head"),
                    help="checkpoint folder (default outputs/odca-head; name assets/checkpoints/odca-head to replace "
                         "the shipped head)")
    tr.add_argument("--epochs", type=_count, default=800)
    tr.add_argument("--seed", type=int, default=0)

    ev = sub.add_parser("evaluate", help="score an ODCA checkpoint against raw depth on a dataset's test split "
                                         "(weak/mid/strong presets, clean pass-through)")
    ev.add_argument("--checkpoint", type=Path, default=None, help="ODCA folder (default: the shipped head)")
    ev.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    ev.add_argument("--split", choices=("by_series", "leave_target_out"), default="by_series",
                    help="split scheme whose test series are scored (default by_series)")
    ev.add_argument("--json", action="store_true", help="print one JSON object instead of the table")

    ol = sub.add_parser("odca-latency", help="per-step latency of the online ODCA module (median, p99)")
    ol.add_argument("--steps", type=_count, default=2000)
    ol.add_argument("--threads", type=_count, default=1, help="torch threads (default 1)")
    ol.add_argument("--json", action="store_true", help="print one JSON object")

    ob = sub.add_parser("bench", help="the offline repair benchmark: raw, LiDAR, EKF, Chronos-2, SOFTS, NHITS, DLinear, "
                                      "NLinear and ODCA on both splits and presets (tables, figures, results.json)")
    ob.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    ob.add_argument("--out", type=Path, default=Path("outputs/bench"), help="results folder (default outputs/bench)")
    ob.add_argument("--split", choices=("by_series", "leave_target_out", "both"), default="both",
                    help="split scheme(s) to run (default both)")
    ob.add_argument("--seed", type=int, default=0, help="training and bootstrap seed (default 0)")
    ob.add_argument("--quick", action="store_true",
                    help="a few series per split and short training (about a minute; not a result to quote)")
    ob.add_argument("--no-ablation", action="store_true", help="skip the loss ablation (five head trainings)")
    ob.add_argument("--max-steps", type=_count, default=None,
                    help="optimiser steps of the neuralforecast baselines (default 600; --quick 15)")
    ob.add_argument("--epochs", type=_count, default=None, help="ODCA head epochs (default 800; --quick 40)")
    ob.add_argument("--json", action="store_true", help="print the results as one JSON object instead of the table")

    bl = sub.add_parser("bench-loop", help="closed-loop throughput: real-time factor on one core (clean, attack + "
                                           "ODCA), sweep episodes per minute with 1 / 2 workers and on Ray")
    bl.add_argument("-n", type=_count, default=8, help="episodes per real-time-factor setting (default 8)")
    bl.add_argument("--rate-episodes", type=_count, default=24,
                    help="episodes per throughput run, timed once the workers are up (default 24)")
    bl.add_argument("--no-ray", action="store_true", help="skip the Ray measurement")
    bl.add_argument("--json", action="store_true", help="print one JSON object")

    bd = sub.add_parser("bench-detector", help="stop-sign detector recall and false-positive frames on rendered drives")
    bd.add_argument("--seed", type=int, default=0)
    bd.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    return p


def _episode_flags(p: argparse.ArgumentParser) -> None:
    """The flags ``racf trial`` and ``racf trials`` share: what runs and how."""
    p.add_argument("--setting", default=None,
                   help="clean or attack, then extra attacks and an estimator joined by '+', e.g. attack+odca, "
                        "attack+lidar_spoof+odca (default clean; --attack/--estimator compose one instead)")
    p.add_argument("--attack", default=None, metavar="A[,B]",
                   help="attacks, comma-separated: patch, lidar_spoof, lidar_dropout (default none)")
    p.add_argument("--estimator", default=None, help="distance estimator: raw, odca, ekf or chronos (default raw)")
    p.add_argument("--rho", type=_share, nargs="+", default=None, metavar="R",
                   help="patch coverage, a value or LOW HIGH (uniform), in [0, 1] (default 0.9 1.0)")
    p.add_argument("--t-atk", type=_duration, nargs="+", default=None, metavar="S",
                   help="attack duration s, a value or LOW HIGH (uniform) (default 0.5 3.0)")
    p.add_argument("--delay-ms", type=float, default=0.0,
                   help="perception-to-actuation delay, ms (default 0; the paper's offboard loop: 49)")
    p.add_argument("--control-hz", type=float, default=None, help="controller rate, Hz (default: every 50 Hz step)")
    p.add_argument("--stable-steps", type=int, default=None,
                   help="steps the sign must be visible before an attack may start (default: the braking "
                        "controller's confirm_frames + 3 = 6)")


def _episode_params(args: argparse.Namespace, command: str, table: bool = False) -> tuple[str | None, dict]:
    """The setting and the spec fields the episode flags give; SystemExit(2) naming what is wrong.
    With ``table`` the settings are the table's own: none may be given, and the setting is None."""
    from experiments.episode import STRONG_RHO, STRONG_T_ATK_S, parse_setting, setting_name

    def fail(msg: str):
        print(f"racf {command}: {msg}", file=sys.stderr)
        raise SystemExit(2)

    try:
        if table and (args.setting is not None or args.attack is not None or args.estimator is not None):
            fail("--table runs its own settings; drop --setting/--attack/--estimator")
        if args.setting is not None and (args.attack is not None or args.estimator is not None):
            fail("give --setting, or --attack/--estimator, not both")
        if table:
            setting = None
        elif args.setting is not None:
            setting = args.setting
            parse_setting(setting)
        else:
            attacks = [a.strip() for a in args.attack.split(",") if a.strip()] if args.attack else []
            setting = setting_name(attacks, args.estimator or "raw")
        if setting is not None and not parse_setting(setting)[0] and (args.rho is not None or args.t_atk is not None):
            fail("--rho and --t-atk apply to settings with an attack")
        params = {"rho": _pair("--rho", args.rho, STRONG_RHO), "t_atk": _pair("--t-atk", args.t_atk, STRONG_T_ATK_S),
                  "delay_ms": args.delay_ms, "control_hz": args.control_hz, "stable_steps": args.stable_steps}
    except ValueError as err:
        fail(str(err))
    return setting, params


def _speed(value: str) -> float:
    v = float(value)
    if not 0.1 <= v <= 3.0:
        raise argparse.ArgumentTypeError(f"speed must be in [0.1, 3.0] m/s, got {value}")
    return v


def _share(value: str) -> float:
    v = float(value)
    if not 0.0 <= v <= 1.0:
        raise argparse.ArgumentTypeError(f"rho must be in [0, 1], got {value}")
    return v


def _duration(value: str) -> float:
    v = float(value)
    if not 0.0 <= v <= 60.0:
        raise argparse.ArgumentTypeError(f"t-atk must be in [0, 60] s, got {value}")
    return v


def _pair(name: str, values: list[float] | None, default: tuple[float, float]) -> tuple[float, float]:
    if values is None:
        return default
    if len(values) > 2 or (len(values) == 2 and values[0] > values[1]):
        raise SystemExit(f"racf trials: {name} takes a value or LOW HIGH with LOW <= HIGH, got {values}")
    return (values[0], values[-1])


def _count(value: str) -> int:
    try:
        n = int(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {value!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {n}")
    return n


def _fmt_ci(lo: float, hi: float, digits: int = 2) -> str:
    return f"[{lo:.{digits}f}, {hi:.{digits}f}]"


def _sweep(args) -> int:
    from experiments.sweeps.report import report_from_store

    if args.report is not None:
        try:
            paths = report_from_store(args.report)
        except ValueError as err:
            print(f"racf sweep: {err}", file=sys.stderr)
            return 2
        print("\n".join(str(p) for p in paths.values()))
        return 0
    fields = {key: value for key, value in (("name", args.name), ("mode", args.mode), ("n", args.n),
                                             ("repeats", args.repeats), ("seed", args.seed),
                                             ("log_steps", args.log_steps)) if value is not None}
    space = {key: value for key, value in (("attack", args.attack), ("estimator", args.estimator),
                                           ("rho", args.rho), ("t_atk", args.t_atk), ("speed", args.speed),
                                           ("sign", args.sign)) if value is not None}
    if args.spec is None and not (space or fields):
        print("racf sweep: give a spec (e.g. smoke.toml), axis flags (--attack, --estimator, --rho, ...) "
              "or --report DIR", file=sys.stderr)
        return 2
    from experiments.sweeps.run import run_sweep
    from experiments.sweeps.spec import parse_spec, spec_text

    try:
        text = spec_text(args.spec, fields, space)
        source = " with ".join(x for x in (str(args.spec) if args.spec is not None else "",
                                           "flags" if fields or space else "") if x)
        spec = parse_spec(text, source, default_name=args.spec.stem if args.spec is not None else "sweep")
        out = args.out or Path("outputs/sweeps") / spec.name
        summary = run_sweep(spec, text, out, backend=args.backend, workers=args.workers,
                            address=args.address, progress=not args.json)
    except ValueError as err:
        print(f"racf sweep: {err}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        print((out / "summary.md").read_text())
        print(f"{summary['n']} episodes ({summary['done']} run, {summary['reused']} reused) in "
              f"{summary['wall_s']:.0f} s; results in {out}")
    return 0


def _view(path: Path) -> int:
    """Opens the rerun viewer on ``path``, or says how to where there is no display."""
    import shutil
    import subprocess

    if path.suffix != ".rrd" or not path.is_file():
        print(f"racf view: {path} is not a rerun recording (.rrd); `racf demo` and `racf trial --rerun PATH` "
              "write them", file=sys.stderr)
        return 2
    viewer = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        print(f"no display here. Open the recording where there is one: `rerun {path}` (pip install "
              f"rerun-sdk==0.41.*), or serve it to a browser: `{viewer} --serve-web {path}` and open the "
              "address it prints (forward its ports over ssh if the machine is remote).")
        return 0
    return subprocess.call([viewer, str(path)])


def _bench(args) -> int:
    from dataclasses import replace

    from experiments.offline.benchmark import BenchConfig, load_splits, run_benchmark
    from experiments.offline.report import main_table, strict, write_report

    if not (args.dataset / "dataset.parquet").exists():
        print(f"racf bench: no dataset at {args.dataset} (make one with `racf collect --out {args.dataset}`)",
              file=sys.stderr)
        return 2
    splits = ("by_series", "leave_target_out") if args.split == "both" else (args.split,)
    common = dict(data=args.dataset, out=args.out, splits=splits, seed=args.seed, ablation=not args.no_ablation)
    cfg = BenchConfig.quick_config(**common) if args.quick else BenchConfig(**common)
    if args.max_steps is not None:
        cfg = replace(cfg, nf=replace(cfg.nf, max_steps=args.max_steps))
    if args.epochs is not None:
        cfg = replace(cfg, odca_epochs=args.epochs)
    try:
        datasets = load_splits(cfg)
    except (ValueError, FileNotFoundError) as err:
        print(f"racf bench: {err}", file=sys.stderr)
        return 2
    results = run_benchmark(cfg, progress=True, datasets=datasets)
    paths = write_report(results, args.out)
    if args.json:
        print(json.dumps(strict({k: v for k, v in results.items() if k != "_traces"}), allow_nan=False))
    else:
        print(main_table(results))
        print(f"ODCA on clean input: RMSE against its input {results['clean']['odca_rmse_vs_input']:.4f} m")
        print(f"wall time {results['wall_s']:.0f} s; results in {args.out} (README.md, results.json, tables/, "
              f"figures/: {len([k for k in paths if k not in ('results', 'summary') and not k.startswith('table')])} "
              "PNGs)")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "snapshot":
        from experiments.viz.snapshot import snapshot

        for path in snapshot(args.out, sign=args.sign, run_up_m=args.run_up, width=args.width,
                             height=args.height, seed=args.seed):
            print(path)
    elif args.command == "bench-sim":
        from experiments.bench.sim import bench_sim

        if args.steps < 10:
            print("racf bench-sim: --steps must be >= 10", file=sys.stderr)
            return 2
        rows = bench_sim(steps=args.steps)
        if args.json:
            print(json.dumps({r.setting: {"steps_per_s": round(r.steps_per_s, 1),
                                          "real_time_factor": round(r.real_time_factor, 2)} for r in rows}))
        else:
            print(f"{'setting':<28}{'steps/s':>10}{'real-time factor':>18}")
            for r in rows:
                print(f"{r.setting:<28}{r.steps_per_s:>10.1f}{r.real_time_factor:>18.2f}")
            print("real-time factor = simulated seconds per wall-clock second at the 50 Hz control rate")
    elif args.command == "demo":
        from experiments.viz.demo import run_demo

        from experiments.viz.demo import demo_table

        summary = run_demo(args.out, sign=args.sign, speed=args.speed, seed=args.seed)
        print(demo_table(summary))
        print("\nrerun recordings (open with `racf view PATH`):")
        for run in summary["runs"]:
            print(f"  {run['rrd']}")
        print(f"distance traces: {summary['png']}")
    elif args.command == "trial":
        from experiments.episode import TrialSpec, run_trial

        setting, params = _episode_params(args, "trial")
        try:
            spec = TrialSpec(setting, args.sign, args.speed, args.seed, target=args.target, **params)
        except ValueError as err:
            print(f"racf trial: {err}", file=sys.stderr)
            return 2
        recorder = None
        if args.rerun is not None:
            from experiments.viz.rerun_log import FrameRecorder

            recorder = FrameRecorder()
        result, log = run_trial(spec, on_step=recorder)
        if recorder is not None:
            from experiments.viz.rerun_log import write_rrd

            write_rrd(args.rerun, log, recorder, title=f"racf trial {spec.trial_id}")
        args.out.mkdir(parents=True, exist_ok=True)
        log.to_parquet(args.out / f"{spec.trial_id}.parquet", index=False)
        (args.out / f"{spec.trial_id}.json").write_text(json.dumps(result.to_dict(), indent=2, allow_nan=False))
        print(json.dumps({**result.to_dict(), "log": str(args.out / f"{spec.trial_id}.parquet")}, indent=2,
                         allow_nan=False))
    elif args.command == "trials":
        return _trials(args)
    elif args.command == "collect":
        from experiments.data.dataset import DEFAULT_DRIVES, collect, load_dataset, summarize_dataset

        path = collect(args.out, drives=args.drives or DEFAULT_DRIVES, seed=args.seed, workers=args.workers,
                       progress=True)  # the bar is on stderr; --summary JSON stays alone on stdout
        ds = load_dataset(args.out)
        summary = summarize_dataset(ds.frame, ds.splits)
        if args.summary:
            print(json.dumps(summary))
        else:
            print(json.dumps(summary, indent=1))
            print(f"dataset: {path}; card: {args.out / 'dataset_card.md'}; plot: {args.out / 'series.png'}")
    elif args.command == "pretrain-prior":
        return _pretrain_prior(args)
    elif args.command == "train":
        return _train(args)
    elif args.command == "evaluate":
        from experiments.data.dataset import load_dataset
        from odca.online import ODCA
        from odca.train import evaluate

        report = evaluate(ODCA.load(args.checkpoint), load_dataset(args.dataset, split=args.split))
        print(json.dumps(report) if args.json else _train_table(report))
    elif args.command == "bench":
        return _bench(args)
    elif args.command == "bench-loop":
        from experiments.bench.loop import bench_loop

        r = bench_loop(n_rtf=args.n, n_rate=args.rate_episodes, ray=not args.no_ray, progress=not args.json)
        if args.json:
            print(json.dumps(r, allow_nan=False))
        else:
            for key, value in r.items():
                print(f"{key:<22}{value:.2f}" if isinstance(value, float) else f"{key:<22}{value}")
            print(f"against the goals: rtf_attack_odca / 3 = {r['rtf_attack_odca'] / 3:.2f}, "
                  f"scaling_efficiency / 0.9 = {r['scaling_efficiency'] / 0.9:.2f} (>= 1 meets each)")
    elif args.command == "sweep":
        return _sweep(args)
    elif args.command == "view":
        return _view(args.path)
    elif args.command == "odca-latency":
        from experiments.bench.odca_latency import odca_latency

        r = odca_latency(steps=args.steps, threads=args.threads)
        if args.json:
            print(json.dumps(r))
        else:
            print(f"ODCA step on the CPU ({r['threads']} thread, prior every {r['refresh_steps']} steps): "
                  f"median {r['median_ms']:.3f} ms, p99 {r['p99_ms']:.3f} ms, max {r['max_ms']:.2f} ms over {r['steps']} "
                  f"steps; median / 2 ms goal = {r['median_ms'] / 2:.2f}; paper's offboard loop 49 ms")
    elif args.command == "attack-study":
        return _attack_study(args)
    elif args.command == "bench-detector":
        from experiments.bench.detector import bench_detector

        r = bench_detector(seed=args.seed, progress=not args.json)
        if args.json:
            print(json.dumps(r.to_dict()))
        else:
            print(f"frames {r.n_frames}, ms per frame {r.ms_per_frame:.2f}")
            print(f"recall (signs 0.5-2.5 m, N = {r.n_positive}): {r.recall:.3f} {_fmt_ci(*r.recall_ci)}  "
                  + "  ".join(f"sign {s}: {v:.3f}" for s, v in r.recall_by_sign.items()))
            print(f"false-positive frames: {r.n_fp_frames} / {r.n_frames} = {r.fp_rate:.4f} {_fmt_ci(*r.fp_rate_ci, digits=4)}")
            print("mean confidence with a share of the sign's box occluded:")
            for side, row in r.occlusion_confidence.items():
                print(f"  from the {side:<5}" + "".join(f"  {q:.1f}: {c:.2f}" for q, c in row.items()))
    return 0


def _trials(args: argparse.Namespace) -> int:
    from experiments.trials import batch_specs, run_batch, run_table, summarize

    if args.table:
        _, params = _episode_params(args, "trials", table=True)
        try:
            table = run_table(args.n, args.out or Path("outputs/table"), seed=args.seed, workers=args.workers,
                              progress=not args.json, rerun=args.rerun, **params)
        except ValueError as err:
            print(f"racf trials: {err}", file=sys.stderr)
            return 2
        if args.json:
            print(json.dumps(table, allow_nan=False))
        else:
            print(_table_text(table))
        return 0
    setting, params = _episode_params(args, "trials")
    try:
        specs = batch_specs(setting, args.n, args.seed, **params)
    except ValueError as err:
        print(f"racf trials: {err}", file=sys.stderr)
        return 2
    out = args.out or Path("outputs/trials") / setting
    results = run_batch(specs, out, workers=args.workers, progress=not args.json, rerun=args.rerun)
    summary = summarize(results)
    if args.json:
        print(json.dumps(summary, allow_nan=False))
        return 0
    print(f"{'sign':>4} {'speed':>6} {'N':>3} {'SCR':>5} {'dt_brake s (mean +- std)':>26}  failures")
    for (sign, speed), group in results.groupby(["sign", "speed"]):
        lat = group.loc[group["success"], "dt_brake_s"].astype(float).dropna()
        lat_text = f"{lat.mean():.3f} +- {lat.std(ddof=1) if len(lat) > 1 else 0:.3f}" if len(lat) else "-"
        failures = ", ".join(f"{k} {v}" for k, v in group["failure"].dropna().value_counts().items()) or "-"
        print(f"{sign:>4} {speed:>6.1f} {len(group):>3} {group['success'].mean():>5.2f} {lat_text:>26}  {failures}")
    print(_table_text({setting: summary}))
    print(f"results: {out / 'results.parquet'}; per-step logs: {out / 'trials'}")
    return 0


def _table_text(table: dict[str, dict]) -> str:
    """SCR / ASR with Wilson intervals, trigger delay and dt_brake over successes, failures by cause."""
    def ms(mean, std):
        return "-" if mean is None else f"{mean:.3f} +- {std or 0:.3f}"

    lines = [f"{'setting':<26}{'N':>4}{'SCR [95% Wilson]':>20}{'ASR [95% Wilson]':>20}{'trigger delay s':>18}"
             f"{'dt_brake s':>18}{'n':>4}{'SCR, attack before t*':>28}  failures"]
    for name, r in table.items():
        asr = f"{r['asr']:.2f} {_fmt_ci(*r['asr_ci'])}" if r.get("asr") is not None else "-"
        fails = ", ".join(f"{k} {v}" for k, v in r["failures"].items() if v) or "-"
        early = "-" if r.get("scr_attack_before_t_star") is None else \
            f"{r['scr_attack_before_t_star']:.2f} {_fmt_ci(*r['scr_attack_before_t_star_ci'])} ({r['n_attack_before_t_star']})"
        lines.append(f"{name:<26}{r['n']:>4}{r['scr']:>6.2f} {_fmt_ci(*r['scr_ci']):>13}{asr:>20}"
                     f"{ms(r['trigger_delay_mean'], r['trigger_delay_std']):>18}"
                     f"{ms(r['dt_brake_mean'], r['dt_brake_std']):>18}{r['n_latency']:>4}{early:>28}  {fails}")
    lines.append("trigger delay = t(brake) - t*; dt_brake = t* to braking within 0.60 m of the line (the paper's "
                 "latency); both over successful stops (n). SCR, attack before t*: the trials whose attack began before t* (their count). Paper (QCar 2, N = 30): clean SCR 1.00, dt 0.165 s; "
                 "attack 0.17, 2.65 s; attack + ODCA 0.80, 0.190 s")
    return "\n".join(lines)


def _pretrain_prior(args: argparse.Namespace) -> int:
    import torch

    from odca.pretrain import pretrain_prior
    from odca.prior import SHIPPED_PRIOR

    torch.manual_seed(args.seed)
    sim_series = None
    if (args.dataset / "dataset.parquet").exists():
        from experiments.data.dataset import load_dataset

        test = load_dataset(args.dataset).clean("test")
        sim_series = [g["d_clean"].to_numpy(np.float32) for _, g in test.groupby("series_id", sort=False)]
    else:
        print(f"no dataset at {args.dataset}: scoring on synthetic series only", file=sys.stderr)
    meta = pretrain_prior(args.out, steps=args.steps, n_series=args.series, seed=args.seed,
                          sim_series=sim_series)
    if args.out.resolve() != SHIPPED_PRIOR.resolve():
        print(f"wrote {args.out}; the shipped prior ({SHIPPED_PRIOR}) is unchanged", file=sys.stderr)
    print(json.dumps(meta, indent=1))
    return 0


def _train(args: argparse.Namespace) -> int:
    from experiments.data.dataset import load_dataset
    from odca.online import SHIPPED_HEAD
    from odca.prior import Chronos2Prior
    from odca.train import train_odca

    dataset = load_dataset(args.dataset, split=args.split)
    model, report = train_odca(dataset, Chronos2Prior(), epochs=args.epochs, seed=args.seed)
    out = args.out
    model.save(out)
    (out / "train_report.json").write_text(json.dumps(report, indent=1))
    print(json.dumps(report, indent=1))
    print(_train_table(report))
    shipped = " (the shipped head)" if out.resolve() == SHIPPED_HEAD.resolve() else \
        f"; the shipped head ({SHIPPED_HEAD}) is unchanged"
    print(f"head parameters: {report['head_parameters']}; checkpoint: {out}{shipped}")
    return 0


def _train_table(report: dict) -> str:
    """The test-split table of a training report: raw depth against ODCA per preset, and clean pass-through."""
    def f(v):
        return "-" if v is None else f"{v:.4f}"

    lines = [f"test split ({report['split']}); RMSE/MAE in m against d_clean (all, moving) and against d_true",
             f"{'preset':<8}{'N':>7}{'N moving':>9}{'RMSE raw':>10}{'RMSE ODCA':>11}{'moving raw':>12}"
             f"{'moving ODCA':>13}{'MAE raw':>9}{'MAE ODCA':>10}{'vs true raw':>13}{'vs true ODCA':>14}"]
    for preset, r in report["test"].items():
        lines.append(f"{preset:<8}{r['n']:>7}{r['n_moving']:>9}{f(r['rmse_raw']):>10}{f(r['rmse']):>11}"
                     f"{f(r['rmse_moving_raw']):>12}{f(r['rmse_moving']):>13}{f(r['mae_raw']):>9}{f(r['mae']):>10}"
                     f"{f(r['rmse_true_raw']):>13}{f(r['rmse_true']):>14}")
    p = report["clean_pass_through"]
    lines.append(f"clean pass-through (input = d_clean): unchanged on {p['unchanged_share_both_present']:.2%} of "
                 f"{p['n_both_present']} steps with depth and LiDAR; RMSE vs input {p['rmse_vs_input']:.4f} m over "
                 f"{p['n_depth']} steps with depth; changed > 1 cm on {p['changed_over_1cm_share']:.2%}")
    return "\n".join(lines)


def _attack_study(args: argparse.Namespace) -> int:
    from experiments.attack_study import run_study

    names = list(dict.fromkeys(args.studies or ("persistence", "coverage", "strong")))
    unknown = [n for n in names if n not in ("persistence", "coverage", "strong")]
    if unknown:
        print(f"racf attack-study: unknown study {unknown}; choose from persistence, coverage, strong", file=sys.stderr)
        return 2
    tables = {}
    for name in names:
        n = max(args.n, 30) if name == "strong" else args.n
        tables[name] = run_study(name, n, args.out, seed=args.seed, workers=args.workers, progress=not args.json)
    if args.json:
        print(json.dumps(tables))
        return 0
    for name, rows in tables.items():
        print(f"\n{name} (no defence)")
        print(f"{'setting':<42}{'N':>4}{'lost frames':>13}{'ASR [95% Wilson]':>22}{'SCR':>6}{'dt_brake s':>18}")
        for r in rows:
            lat = f"{r['dt_brake_mean']:.2f} +- {r['dt_brake_std'] or 0:.2f} ({r['n_latency']})" if r["n_latency"] else "-"
            print(f"{r['label']:<42}{r['n']:>4}{r['lost_frames_mean']:>13.1f}"
                  f"{r['asr']:>8.2f} {_fmt_ci(*r['asr_ci']):>13}{r['scr']:>6.2f}{lat:>18}")
    print(f"\ntrials and logs under {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
