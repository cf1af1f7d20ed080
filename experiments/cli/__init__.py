"""The ``racf`` command line: one module per command group, each registering its subcommands
and their handlers. Parsing and printing only; the work lives in the packages beside this one."""

from __future__ import annotations

import argparse
import sys

from racf.experiments.cli import bench, data, detector, falsify, odca, scorecard, sweep, trials, view
from racf.experiments.cli.common import UsageError, fail, load_plugins_from_argv

__all__ = ["main", "build_parser", "GROUPS"]

#: The command groups, in the order ``racf --help`` lists their commands.
GROUPS = (view, trials, sweep, scorecard, falsify, data, odca, detector, bench)


def build_parser() -> argparse.ArgumentParser:
    import racf

    p = argparse.ArgumentParser(prog="racf", description="RACF testbed: QCar 2 simulation, attacks and ODCA.")
    p.add_argument("--version", action="version", version=f"racf {racf.__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    for group in GROUPS:
        group.register(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    """Runs one command; returns its exit code (2: bad input, nothing run)."""
    from racf.experiments.sweeps.executors import CodeChangedError
    from racf.odca.prior import CheckpointError
    from racf.plugins import PluginError

    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        load_plugins_from_argv(argv)  # plug-ins first: the parser's choices and help list them
        args = build_parser().parse_args(argv)
        if getattr(args, "address", None) is not None and args.backend != "ray":
            fail(args.command, "--address joins a Ray cluster: it needs --backend ray")
        return args.handler(args)
    except UsageError as err:
        print(err, file=sys.stderr)
        return 2
    except PluginError as err:  # a user's plug-in that cannot load, or a name no registry knows
        print(f"racf: {err}", file=sys.stderr)
        return 2
    except CodeChangedError as err:  # the source was edited mid-run: nothing stale is stored
        print(f"racf {argv[0] if argv else ''}: {err}".replace(" :", ":"), file=sys.stderr)
        return 2
    except CheckpointError as err:  # a checkpoint a user named that is missing or corrupt
        print(f"racf {argv[0] if argv else ''}: {err}".replace(" :", ":"), file=sys.stderr)
        return 2
