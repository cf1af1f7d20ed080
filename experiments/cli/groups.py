"""The command line by group: ``racf bench sim``, ``racf odca train``, ``racf detector data``.

Each command is declared once, where its module registers it under its flat name
(``bench-sim``, ``train``, ``detector-data``); a group gives it its short name beside its
siblings, with the same flags and handler (argparse's ``parents``). The flat names stay as
hidden aliases that still work, so scripts written for the flat command line run unchanged;
``racf bench`` with the offline benchmark's flags after it is that benchmark, as before.
"""

from __future__ import annotations

import argparse

from racf.experiments.cli.common import Parser

__all__ = ["GROUPS", "add_groups", "canonical_argv"]

#: group -> (what it holds, {short name: the command's flat name}).
GROUPS: dict[str, tuple[str, dict[str, str]]] = {
    "bench": ("benchmarks: the offline repair benchmark and the speed and detector tests",
              {"offline": "bench-offline", "sim": "bench-sim", "loop": "bench-loop", "detector": "bench-detector",
               "radio": "bench-radio", "poses": "bench-poses",
               "traffic": "bench-traffic", "patch": "bench-patch", "odca-latency": "odca-latency", "odca-onboard": "bench-odca-onboard",
               "service": "bench-service", "service-stress": "bench-service-stress", "bags": "bench-bags", "guard": "bench-guard",
               "paired": "bench-paired"}),
    "odca": ("ODCA: pretrain its Chronos-2 prior, train its head, evaluate a checkpoint, export it for the car",
             {"pretrain-prior": "pretrain-prior", "train": "train", "evaluate": "evaluate", "export": "export-odca"}),
    "detector": ("the learned detectors: render the sign segmenter's views, train it, optimise a sticker against it; "
                 "train the vehicle segmenter",
                 {"data": "detector-data", "train": "train-detector", "optimise-patch": "optimise-patch",
                  "train-vehicle": "train-vehicle-detector"}),
    "board": ("the leaderboard: check a card, verify it by running its episodes again, submit it to be set beside "
              "racf's own",
              {"check": "board-check", "verify": "board-verify", "submit": "board-submit"}),
    "bag": ("ROS 2 bags on Quanser's QCar 2 topics: export an episode, replay the car's software on a recording, "
            "show what a bag holds",
            {"export": "export-bag", "replay": "replay-bag", "info": "bag-info"}),
}
#: What ``racf bench FLAGS`` (no subcommand) was before the groups: the offline benchmark.
_BARE = {"bench": "bench-offline"}


def add_groups(sub: argparse._SubParsersAction) -> None:
    """Adds each group (its commands made from the flat ones' parsers) and hides the flat names from
    the top-level help; call it after every command is registered."""
    helps = {action.dest: action.help for action in sub._choices_actions}
    grouped = {flat for _, commands in GROUPS.values() for flat in commands.values()}
    for name, (what, commands) in GROUPS.items():
        group = sub.add_parser(name, help=what, description=what)
        inner = group.add_subparsers(dest="subcommand", required=True, metavar="COMMAND", parser_class=Parser)
        for short, flat in commands.items():
            parser = sub.choices[flat]
            inner.add_parser(short, parents=[parser], add_help=False, help=helps.get(flat),
                             description=parser.description or helps.get(flat))
    # The flat names still parse; the help lists the groups instead.
    sub._choices_actions[:] = [a for a in sub._choices_actions if a.dest not in grouped]


def canonical_argv(argv: list[str]) -> list[str]:
    """``racf bench --quick`` (the offline benchmark's flags, no subcommand) as ``racf bench-offline --quick``."""
    if argv and argv[0] in _BARE:
        commands = GROUPS[argv[0]][1]
        if len(argv) == 1 or (argv[1] not in commands and argv[1] not in ("-h", "--help")):
            return [_BARE[argv[0]], *argv[1:]]
    return argv
