"""``racf demo``, ``racf snapshot`` and ``racf view``: the story, a picture of the map, recordings."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from racf.experiments.cli.common import output_dir, positive, sensor_flags, sign, speed

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("snapshot", help="top view of the map and the car's camera, depth and LiDAR at a pose (PNGs)")
    s.add_argument("--sign", type=sign, default=2, help="stop sign whose approach the car stands on (0-3, default 2)")
    s.add_argument("--run-up", type=positive, default=1.2, help="front bumper to stop line, m (default 1.2)")
    s.add_argument("--width", type=int, default=320, help="camera width px (default 320)")
    s.add_argument("--height", type=int, default=240, help="camera height px (default 240)")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--out", type=output_dir, default=Path("outputs/snapshot"), help="output folder")
    s.set_defaults(handler=_snapshot)

    d = sub.add_parser("demo", help="the story at one stop sign: clean, patch attack, attack + ODCA; a table, "
                                     "three rerun recordings and a PNG of the distance traces")
    d.add_argument("--sign", type=sign, default=1, help="stop sign 0-3 (default 1)")
    d.add_argument("--speed", type=speed, default=1.5, help="cruise speed m/s, 0.1-3.0 (default 1.5)")
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--out", type=output_dir, default=Path("outputs/demo"), help="output folder")
    sensor_flags(d)
    d.set_defaults(handler=_demo)

    vw = sub.add_parser("view", help="open a rerun recording (.rrd) in the rerun viewer")
    vw.add_argument("path", type=Path, help="the .rrd file (racf demo, racf trial --rerun)")
    vw.set_defaults(handler=_view)


def _snapshot(args: argparse.Namespace) -> int:
    from racf.experiments.viz.snapshot import snapshot

    for path in snapshot(args.out, sign=args.sign, run_up_m=args.run_up, width=args.width, height=args.height,
                         seed=args.seed):
        print(path)
    return 0


def _demo(args: argparse.Namespace) -> int:
    from racf.experiments.viz.demo import demo_table, run_demo

    summary = run_demo(args.out, sign=args.sign, speed=args.speed, seed=args.seed, sensor_profile=args.sensor_profile,
                       sign_geometry=args.sign_geometry)
    print(demo_table(summary))
    print("\nrerun recordings (open with `racf view PATH`):")
    for run in summary["runs"]:
        print(f"  {run['rrd']}")
    print(f"distance traces: {summary['png']}")
    return 0


def _readable_recording(path: Path) -> bool:
    """Whether rerun can read the file's first chunk (a truncated or foreign file cannot)."""
    from rerun.chunk import RrdReader

    try:
        next(iter(RrdReader(path).stream()), None)
    except Exception:  # rerun reports a bad file as RuntimeError, and may change its type
        return False
    return True


def _view(args: argparse.Namespace) -> int:
    """Opens the rerun viewer on the recording, or says how to where there is no display."""
    import shutil
    import subprocess

    path = args.path
    if path.suffix != ".rrd" or not path.is_file() or not _readable_recording(path):
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
