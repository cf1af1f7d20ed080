"""``racf sweep``: Monte Carlo attack sweeps from a TOML spec or flags."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from racf.experiments.cli.common import (attack_help, backend_flags, count, estimator_help, estimator_option_flag,
                                         estimator_options, fail, output_dir, plugin_flag, sensor_flags,
                                         service_flags, service_params)

__all__ = ["register"]


def _shipped_specs() -> list[str]:
    import racf.experiments.sweeps  # the folder of specs, found without the spec module (the episode code)

    return sorted(p.name for p in (Path(racf.experiments.sweeps.__file__).parent / "specs").glob("*.toml"))


def register(sub: argparse._SubParsersAction) -> None:
    sw = sub.add_parser("sweep", help="a Monte Carlo attack sweep from a TOML spec or flags (grid or random draws) "
                                      "on a local process pool or Ray; resumes; summary and SCR plots")
    sw.add_argument("spec", nargs="?", type=Path, default=None,
                    help=f"the sweep spec (TOML); shipped: {', '.join(_shipped_specs())}. "
                         "Without one, the flags below make the sweep")
    sw.add_argument("--out", type=output_dir, default=None, help="results folder (default outputs/sweeps/<spec name>)")
    backend_flags(sw, workers_help="parallel episodes (local processes, or a local Ray's CPUs)")
    sw.add_argument("--json", action="store_true", help='print {"n", "done", "reused", "wall_s", "scr"} as JSON')
    sw.add_argument("--report", type=Path, default=None, metavar="DIR",
                    help="redraw the summary and plots of a stored sweep, running nothing")
    fl = sw.add_argument_group("a sweep from flags (alone, or replacing the spec's fields)")
    fl.add_argument("--name", default=None, help="the sweep's name (default: the spec's, or one made from its content)")
    fl.add_argument("--mode", choices=("grid", "random"), default=None,
                    help="grid: every combination, --repeats seeds each; random: --n draws")
    fl.add_argument("--n", type=count, default=None, help="random mode: draws (each run with every estimator)")
    fl.add_argument("--repeats", type=count, default=None, help="grid mode: seeds per cell")
    fl.add_argument("--seed", type=int, default=None, help="the sweep's seed")
    fl.add_argument("--log-steps", action="store_true", default=None, help="also keep every episode's per-step log")
    sensor_flags(fl, default=None, geometry_default=None)
    fl.add_argument("--attack", nargs="+", default=None, metavar="A",
                    help=f"'none', an attack or '+'-joined attacks: {attack_help()}")
    fl.add_argument("--estimator", nargs="+", default=None, metavar="E", help=estimator_help())
    for flag, what in (("--rho", "patch coverage in [0, 1]"), ("--t-atk", "attack duration s"),
                       ("--speed", "cruise speed m/s")):
        fl.add_argument(flag, nargs="+", type=float, default=None, metavar="X",
                        help=f"{what}: values (grid) or LOW HIGH (random)")
    fl.add_argument("--sign", nargs="+", type=int, default=None, metavar="K", help="stop signs 0-3")
    estimator_option_flag(fl)
    service_flags(fl)
    plugin_flag(sw)
    sw.set_defaults(handler=_sweep)


def _sweep(args: argparse.Namespace) -> int:
    from racf.experiments.sweeps.report import report_from_store

    if args.report is not None:
        try:
            paths = report_from_store(args.report)
        except ValueError as err:
            fail("sweep", str(err))
        print("\n".join(str(p) for p in paths.values()))
        return 0
    fields = {key: value for key, value in (("name", args.name), ("mode", args.mode), ("n", args.n),
                                             ("repeats", args.repeats), ("seed", args.seed),
                                             ("log_steps", args.log_steps),
                                             ("sensor_profile", args.sensor_profile),
                                             ("sign_geometry", args.sign_geometry)) if value is not None}
    fields |= service_params(args, "sweep")
    space = {key: value for key, value in (("attack", args.attack), ("estimator", args.estimator),
                                           ("rho", args.rho), ("t_atk", args.t_atk), ("speed", args.speed),
                                           ("sign", args.sign)) if value is not None}
    if args.estimator_option:
        from racf.plugins import ESTIMATORS

        default = args.estimator[0] if args.estimator and len(args.estimator) == 1 else None
        fields["estimators"] = estimator_options("sweep", args.estimator_option, tuple(ESTIMATORS), default)
    if args.spec is None and not (space or fields):
        fail("sweep", "give a spec (e.g. smoke.toml), axis flags (--attack, --estimator, --rho, ...) or --report DIR")
    from racf.experiments.sweeps.run import run_sweep
    from racf.experiments.sweeps.spec import parse_spec, spec_text

    try:
        text = spec_text(args.spec, fields, space)
        source = " with ".join(x for x in (str(args.spec) if args.spec is not None else "",
                                           "flags" if fields or space else "") if x)
        spec = parse_spec(text, source, default_name=args.spec.stem if args.spec is not None else "sweep")
        out = args.out or Path("outputs/sweeps") / spec.name
        summary = run_sweep(spec, text, out, backend=args.backend, workers=args.workers,
                            address=args.address, progress=not args.json)
    except ValueError as err:
        fail("sweep", str(err))
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        print((out / "summary.md").read_text())
        print(f"{summary['n']} episodes ({summary['done']} run, {summary['reused']} reused) in "
              f"{summary['wall_s']:.0f} s; results in {out}")
    return 0
