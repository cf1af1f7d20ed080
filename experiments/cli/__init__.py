"""The ``racf`` command line: one module per command group, each registering its subcommands
and their handlers. Parsing and printing only; the work lives in the packages beside this one."""

from __future__ import annotations

import argparse
import sys

from experiments.cli import bench, data, detector, odca, sweep, trials, view
from experiments.cli.common import UsageError, fail

__all__ = ["main", "build_parser", "GROUPS"]

#: The command groups, in the order ``racf --help`` lists their commands.
GROUPS = (view, trials, sweep, data, odca, detector, bench)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="racf", description="RACF testbed: QCar 2 simulation, attacks and ODCA.")
    sub = p.add_subparsers(dest="command", required=True)
    for group in GROUPS:
        group.register(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    """Runs one command; returns its exit code (2: bad input, nothing run)."""
    args = build_parser().parse_args(argv)
    try:
        if getattr(args, "address", None) is not None and args.backend != "ray":
            fail(args.command, "--address joins a Ray cluster: it needs --backend ray")
        return args.handler(args)
    except UsageError as err:
        print(err, file=sys.stderr)
        return 2
