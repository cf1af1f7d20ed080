"""The ``racf`` command line."""

from __future__ import annotations

import argparse
import json
import sys
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

    d = sub.add_parser("demo", help="drive one stop-sign approach and write pictures")
    d.add_argument("--sign", type=_sign, default=2, help="stop sign 0-3 (default 2)")
    d.add_argument("--speed", type=_positive, default=1.0, help="cruise speed m/s (default 1.0)")
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--out", type=Path, default=Path("outputs/demo"), help="output folder")
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "snapshot":
        from experiments.snapshot import snapshot

        for path in snapshot(args.out, sign=args.sign, run_up_m=args.run_up, width=args.width,
                             height=args.height, seed=args.seed):
            print(path)
    elif args.command == "bench-sim":
        from experiments.bench_sim import bench_sim

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
        from experiments.demo import run_demo

        summary = run_demo(args.out, sign=args.sign, speed=args.speed, seed=args.seed)
        print(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
