"""``racf bag export|replay|info`` (flat: ``export-bag``, ``replay-bag``, ``bag-info``): episodes as
ROS 2 bags on Quanser's topics, and the car's software on a recording."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from racf.experiments.cli.common import fail, keyed_values, output_dir, plugin_flag
from racf.experiments.cli.episode_flags import trial_flags, trial_spec

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    register_bench(sub)
    e = sub.add_parser("export-bag", help="run an episode (racf trial's flags) and write it as a ROS 2 bag (MCAP) "
                                          "on Quanser's QCar 2 topics, with racf's signals under /racf/",
                       description="Runs the episode racf trial's flags describe (its id makes the run "
                                   "reproducible) and writes what the car's software received, step by step, as a "
                                   "rosbag2 folder in MCAP: Quanser's topics, names, types and conventions, with "
                                   "the defence's distance, gate and flag and the ground truth under /racf/.")
    e.add_argument("bag", type=Path, metavar="BAG", help="the bag folder to write (must not exist)")
    trial_flags(e)
    e.add_argument("--json", action="store_true", help="print one JSON object")
    e.set_defaults(handler=_export)

    r = sub.add_parser("replay-bag", help="run the car's software (perception, tracker, localisation, defence, "
                                          "braker) on a recorded bag, with no simulator: the step log and a rerun "
                                          "recording",
                       description="Replays a rosbag2 (racf's, or your QCar 2's through --mapping) into the car's "
                                   "software step by step at 50 Hz and writes the per-step log (Parquet), a JSON "
                                   "summary and, with --rerun, a rerun recording. Ground truth is in the log only "
                                   "where the bag carries it.")
    r.add_argument("bag", type=Path, metavar="BAG", help="the bag folder (holding metadata.yaml)")
    r.add_argument("--mapping", type=Path, default=None, metavar="TOML",
                   help="how another recording's topics, camera and LiDAR meet the car (the tutorial's mapping file)")
    r.add_argument("--defence", default=None, metavar="NAME",
                   help="the defence (estimator) to run (default: the bag's own; raw for a bag racf did not write)")
    r.add_argument("--attack", default=None, metavar="A[,B]",
                   help="observation-space attacks to apply to the recording, comma-separated (those that need "
                        "the simulator are refused)")
    r.add_argument("--attack-param", action="append", default=[], metavar="ATTACK.KEY=VALUE",
                   help="a setting of one of the attacks (repeatable; TOML values), e.g. "
                        "depth_bias.trigger=at_time depth_bias.start_s=1.0")
    r.add_argument("--out", type=output_dir, default=Path("outputs/replay"), help="output folder")
    r.add_argument("--rerun", type=Path, default=None, metavar="PATH", help="also write a rerun recording (.rrd)")
    r.add_argument("--json", action="store_true", help="print one JSON object")
    plugin_flag(r)
    r.set_defaults(handler=_replay)

    i = sub.add_parser("bag-info", help="a bag's topics, types, counts, rates and duration")
    i.add_argument("bag", type=Path, metavar="BAG", help="the bag folder (holding metadata.yaml)")
    i.add_argument("--json", action="store_true", help="print one JSON object")
    i.set_defaults(handler=_info)


def _export(args: argparse.Namespace) -> int:
    from racf.experiments.bags.export import export_episode
    from racf.experiments.episode.preflight import check_specs

    spec = trial_spec(args, "export-bag")
    if args.bag.exists():
        fail("export-bag", f"{args.bag} exists; remove it or choose another path for the bag")
    check_specs([spec])
    start = time.perf_counter()
    summary = export_episode(spec, args.bag)
    wall = time.perf_counter() - start
    size = sum(f.stat().st_size for f in args.bag.rglob("*") if f.is_file())
    out = {"bag": str(summary.path), "trial_id": summary.trial_id, "steps": summary.steps,
           "simulated_s": summary.duration_s, "wall_s": round(wall, 2),
           "wall_per_simulated_s": round(wall / max(summary.duration_s, 1e-9), 3), "megabytes": round(size / 1e6, 1),
           "messages": sum(summary.counts.values()), "topics": len(summary.counts), "result": summary.result}
    if args.json:
        print(json.dumps(out, indent=2, allow_nan=False))
    else:
        print(f"wrote {out['bag']}: {summary.steps} steps ({summary.duration_s:.2f} s simulated), "
              f"{out['messages']} messages on {out['topics']} topics, {out['megabytes']} MB, in {wall:.1f} s "
              f"({out['wall_per_simulated_s']:.2f} s per simulated s)")
        print(f"episode {summary.trial_id}; see it with `racf bag-info {out['bag']}`, replay it with "
              f"`racf replay-bag {out['bag']}`")
    return 0


def _replay(args: argparse.Namespace) -> int:
    from racf.experiments.bags.mapping import Mapping
    from racf.experiments.bags.replay import replay_bag
    from racf.provenance import atomic_write

    attacks = tuple(a.strip() for a in args.attack.split(",") if a.strip()) if args.attack else ()
    params = keyed_values("replay-bag", "--attack-param", args.attack_param)
    if params and not set(params) <= set(attacks):
        fail("replay-bag", f"--attack-param names attack(s) {sorted(params)}; --attack gives {list(attacks) or 'none'}")
    mapping = Mapping.load(args.mapping)
    start = time.perf_counter()
    replay = replay_bag(args.bag, mapping, args.defence, attacks, params, record=args.rerun is not None)
    wall = time.perf_counter() - start
    args.out.mkdir(parents=True, exist_ok=True)
    name = args.bag.name + ("+" + "+".join(attacks) if attacks else "") + (f"+{args.defence}" if args.defence else "")
    log_path = atomic_write(args.out / f"{name}.parquet", replay.log)
    simulated = float(replay.log["t"].iloc[-1] - replay.log["t"].iloc[0]) if len(replay.log) > 1 else 0.0
    summary = {"bag": str(args.bag), "log": str(log_path), "setting": replay.setting,
               "mapping": mapping.source, "steps": len(replay.log), "recorded_s": round(simulated, 3),
               "wall_s": round(wall, 2), "wall_per_recorded_s": round(wall / max(simulated, 1e-9), 3),
               "ground_truth": not {"d_true", "x"} <= set(replay.absent),
               "absent_columns": list(replay.absent), "offline": replay.scores,
               "brake_steps": int(replay.log["brake"].sum()), "detected_steps": int(replay.log["detected"].sum()),
               "warnings": list(replay.warnings)}
    for warning in replay.warnings:  # on stderr, a line each: the JSON on stdout stays one object
        print(f"racf replay-bag: warning: {warning}", file=sys.stderr)
    atomic_write(args.out / f"{name}.json", json.dumps(summary, indent=2, allow_nan=False))
    if replay.frames is not None:
        from racf.experiments.episode.rerun_log import write_rrd

        write_rrd(args.rerun, replay.log, replay.frames, title=f"racf replay-bag {args.bag.name}")
        summary["rerun"] = str(args.rerun)
    if args.json:
        print(json.dumps(summary, indent=2, allow_nan=False))
        return 0
    print(f"replayed {summary['steps']} steps ({summary['recorded_s']:.2f} s recorded) in {wall:.1f} s; "
          f"setting {summary['setting']}; detections on {summary['detected_steps']} steps, "
          f"brake on {summary['brake_steps']}")
    if summary["ground_truth"]:
        o = replay.scores
        print("offline, against the bag's ground truth: " + ", ".join(
            f"{k} {v:.3f}" for k, v in o.items() if isinstance(v, float)) + f" (N {o['steps']} steps)")
    else:
        print("the bag has no ground truth: the log leaves out the referee's columns and no offline score is given")
    print(f"log {log_path}" + (f"; rerun {args.rerun} (open it with `racf view {args.rerun}`)" if args.rerun else ""))
    return 0


def _info(args: argparse.Namespace) -> int:
    from racf.experiments.bags.info import bag_info

    info = bag_info(args.bag)
    if args.json:
        print(json.dumps(info, indent=2, allow_nan=False))
        return 0
    print(f"{info['path']}: {info['storage']}, {info['messages']} messages, {info['duration_s']:.2f} s"
          + (f", episode {info['trial_id']}" if info.get("trial_id") else ""))
    width = max(len(t["topic"]) for t in info["topics"]) if info["topics"] else 5
    print(f"{'topic':<{width}}  {'type':<38} {'count':>6} {'rate Hz':>8}")
    for t in info["topics"]:
        rate = f"{t['rate_hz']:.1f}" if t["rate_hz"] is not None else "-"
        print(f"{t['topic']:<{width}}  {t['type']:<38} {t['count']:>6} {rate:>8}")
    return 0


def register_bench(sub: argparse._SubParsersAction) -> None:
    b = sub.add_parser("bench-bags", help="the cost of exporting a drive as a bag and replaying it, per simulated "
                                          "second, on this process's core (the goal: each <= 2)")
    b.add_argument("--drive-s", type=float, default=60.0, help="how long the drive is drawn to last, s: within its last "
                                                               "2 s (default 60; at least 7)")
    b.add_argument("--setting", default="clean+odca", help="the drive's setting (default clean+odca)")
    b.add_argument("--seed", type=int, default=0)
    b.add_argument("--out", type=output_dir, default=Path("outputs/bench-bags"), help="where the bag is written")
    b.add_argument("--json", action="store_true", help="print one JSON object")
    b.set_defaults(handler=_bench_bags)


def _bench_bags(args: argparse.Namespace) -> int:
    import shutil

    from racf.experiments.bags.export import export_episode
    from racf.experiments.bags.replay import replay_bag
    from racf.experiments.episode import TrialSpec, run_trial

    try:
        # A drive is drawn to last within a range: the last 2 s below the asked length.
        spec = TrialSpec(args.setting, 0, 1.0, args.seed, target="drive", drive_s=(args.drive_s - 2.0, args.drive_s))
    except ValueError as err:
        fail("bench bags", str(err))
    bag = args.out / "drive"
    shutil.rmtree(bag, ignore_errors=True)
    # Warm: the env, the detector and the defence's models are built once, by a short approach.
    run_trial(TrialSpec(args.setting, 1, 1.0, args.seed))
    timings = {}
    start = time.perf_counter()
    _, log = run_trial(spec)
    timings["episode_s"] = time.perf_counter() - start
    start = time.perf_counter()
    summary = export_episode(spec, bag)
    timings["export_s"] = time.perf_counter() - start
    start = time.perf_counter()
    replay = replay_bag(bag)
    timings["replay_s"] = time.perf_counter() - start
    simulated = float(log["t"].iloc[-1])
    out = {"spec": spec.trial_id, "simulated_s": simulated, "steps": len(log), **{k: round(v, 2) for k, v in timings.items()},
           **{k.replace("_s", "_per_simulated_s"): round(v / simulated, 3) for k, v in timings.items()},
           "bag_megabytes": round(sum(f.stat().st_size for f in bag.rglob("*") if f.is_file()) / 1e6, 1),
           "replay_equal": bool(all(replay.log[c].equals(summary.log[c]) for c in ("d_fused", "brake", "detected")))}
    if args.json:
        print(json.dumps(out, indent=2, allow_nan=False))
        return 0
    print(f"a {simulated:.1f} s drive ({out['steps']} steps, {spec.setting}), one process:")
    for key in ("episode", "export", "replay"):
        print(f"  {key:<8}{out[key + '_s']:>8.1f} s   {out[key + '_per_simulated_s']:.2f} s per simulated s")
    print(f"bag {out['bag_megabytes']} MB; the replay gives back the episode's distances and brakes: "
          f"{out['replay_equal']}")
    return 0

