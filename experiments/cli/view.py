"""``racf demo``, ``racf snapshot``, ``racf moment`` and ``racf view``: the story, a picture of the map,
an episode's moment, recordings."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from racf.experiments.cli.common import output_dir, positive, sensor_flags, sign, speed
from racf.experiments.cli.episode_flags import trial_flags

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

    m = sub.add_parser("moment", help="a picture of an episode at the moment that matters: the camera and the depth "
                                       "when the attack acts and the defence answers, and the distances over the approach",
                       description="Runs the episode racf trial's flags name (or, with --sweep and --episode, one "
                                   "of a sweep's) and draws, from the episode itself, what the car's camera and "
                                   "depth showed at the moment the attack acted and the defence answered, beside what "
                                   "stood there, and the distances over the approach with that moment marked.")
    trial_flags(m)
    m.add_argument("--sweep", type=Path, default=None, metavar="FOLDER",
                   help="a sweep's output folder (holding spec.toml): with --episode, draw one of its episodes")
    m.add_argument("--episode", default=None, metavar="ID", help="the episode's id (its trial_id) in --sweep")
    m.add_argument("--out", type=Path, default=Path("outputs/moment.png"), metavar="PNG",
                   help="the picture to write (default outputs/moment.png)")
    m.set_defaults(handler=_moment)

    vw = sub.add_parser("view", help="open a rerun recording (.rrd) in the rerun viewer")
    vw.add_argument("path", type=Path, help="the .rrd file (racf demo, racf trial --rerun)")
    vw.set_defaults(handler=_view)


def _moment(args: argparse.Namespace) -> int:
    from racf.experiments.cli.common import fail
    from racf.experiments.cli.episode_flags import trial_spec
    from racf.experiments.viz.moment import moment_figure

    if (args.sweep is None) != (args.episode is None):
        fail("moment", "--sweep and --episode go together: the sweep's folder and one of its episode ids")
    spec = _sweep_episode(args.sweep, args.episode) if args.sweep is not None else trial_spec(args, "moment")
    path = moment_figure(spec, args.out)
    print(f"wrote {path}: {spec.trial_id}")
    return 0


def _sweep_episode(folder: Path, episode: str):
    """The spec of one episode of the sweep in ``folder``, by its id."""
    from racf.errors import UserError
    from racf.experiments.sweeps.spec import parse_spec

    spec_file = folder / "spec.toml"
    if not spec_file.is_file():
        raise UserError(f"{folder} holds no sweep (no spec.toml): give the folder racf sweep wrote")
    episodes = {s.trial_id: s for s in parse_spec(spec_file.read_text()).episodes()}
    if episode not in episodes:
        stem = episode.rsplit("_", 1)[0]
        if any(i.rsplit("_", 1)[0] == stem for i in episodes):
            raise UserError(f"episode {episode!r} was run by other code than this checkout's (its ids end in "
                            f"{next(iter(episodes)).rsplit('_', 1)[1]!r}): check out the commit the sweep ran on")
        first = next(iter(episodes), None)
        raise UserError(f"the sweep in {folder} has no episode {episode!r} (its ids look like {first!r}; "
                        "the parts/*.parquet rows name them)")
    return episodes[episode]


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
    if "moment_png" in summary:
        print(f"the moment the attack acts and the defence answers: {summary['moment_png']}")
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
