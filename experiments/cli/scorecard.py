"""``racf scorecard``: rate defences (or an attack) on a named, versioned battery."""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

from racf.experiments.cli.common import (backend_flags, estimator_option_flag, estimator_options, fail, output_dir,
                                         service_flags, service_params,
                                         plain_values, plugin_flag)

__all__ = ["register"]

_DEFAULT_OUT = Path("outputs/scorecard")
_DATASET = Path("data/qcar2")
#: The quick battery's dataset: a few drives, collected once into the output folder.
_QUICK_DRIVES = 6


def register(sub: argparse._SubParsersAction) -> None:
    sc = sub.add_parser("scorecard", help="rate defences (built-in or plug-in) or an attack on the standard battery: "
                                          "closed loop, drives, detection, offline and cost; one card each")
    what = sc.add_mutually_exclusive_group(required=True)
    what.add_argument("--defence", nargs="+", metavar="NAME", help="the defences to rate (racf list shows them)")
    what.add_argument("--attack", metavar="NAME", help="rate an attack against every registered defence")
    what.add_argument("--compare", nargs=2, metavar=("A", "B"),
                      help="two stored cards side by side (a defence's name in --out, or a card's JSON file)")
    from racf.experiments.scorecard.battery_names import BATTERY_NAMES, DEFAULT_BATTERY

    # No argparse choices: a plug-in's or a test's battery registered at run time is one too (checked when it runs).
    sc.add_argument("--battery", default=None, metavar="NAME",
                    help=f"the battery: {', '.join(BATTERY_NAMES)} (default {DEFAULT_BATTERY}, the stop-sign battery the "
                         "leaderboard's paper rows follow; `docs/reference/battery.md` lists each one's rows)")
    sc.add_argument("--target", default=None, metavar="SCENARIO",
                    help="run the battery's stop-sign approaches in this scenario (racf list shows them; its cards "
                         "are named BATTERY@SCENARIO[PARAMETERS])")
    sc.add_argument("--scenario-param", action="append", default=[], metavar="KEY=VALUE",
                    help="a parameter of --target's scenario (repeatable; values are TOML)")
    sc.add_argument("--quick", action="store_true",
                    help="every row at a small N, for development: marked as quick in every output")
    sc.add_argument("--out", type=output_dir, default=_DEFAULT_OUT, help=f"results folder (default {_DEFAULT_OUT}); "
                                                                   "episodes there are reused")
    sc.add_argument("--dataset", type=Path, default=None,
                    help=f"the offline rows' dataset (default {_DATASET}, collected first if missing; "
                         f"--quick: {_QUICK_DRIVES} drives collected into --out)")
    backend_flags(sc, workers_help="parallel episodes (local processes, or a local Ray's CPUs)")
    sc.add_argument("--json", action="store_true", help="print the cards as one JSON object")
    estimator_option_flag(sc)
    service_flags(sc)
    plugin_flag(sc)
    sc.set_defaults(handler=_scorecard)


def _battery(name: str | None):
    from racf.experiments.scorecard.battery import BATTERIES, DEFAULT_BATTERY

    name = name or DEFAULT_BATTERY
    if name not in BATTERIES:
        fail("scorecard", f"unknown battery {name!r}; released: {', '.join(BATTERIES)}")
    return BATTERIES[name]


def _dataset(args: argparse.Namespace, quick: bool):
    from racf.experiments.data.dataset import collect, load_dataset

    path = args.dataset or (args.out / "data-quick" if quick else _DATASET)
    if not (path / "dataset.parquet").exists():
        if args.dataset is not None:
            fail("scorecard", f"no dataset at {path} (make one with `racf collect --out {path}`)")
        print(f"collecting the offline rows' dataset into {path} (once; later cards reuse it)", file=sys.stderr)
        collect(path, drives=_QUICK_DRIVES if quick else 36, workers=args.workers, backend=args.backend,
                address=args.address)
    try:
        return load_dataset(path, split="by_series")
    except (ValueError, FileNotFoundError) as err:
        fail("scorecard", str(err))


def _card_path(out: Path, battery: str, defence: str) -> Path:
    """Where a card is stored: under its battery's name (a scenario's parameters included), made safe
    for a file name (``racf-4@stale_map[case=removed, shift_m=1.0]`` -> ``racf-4@stale_map_case=removed_shift_m=1.0``)."""
    folder = re.sub(r"[^\w.@=+-]+", "_", battery).strip("_")
    return out / "cards" / folder / f"{defence}.json"


def _load_card(args: argparse.Namespace, ref: str, battery: str) -> dict:
    path = Path(ref) if Path(ref).suffix == ".json" else _card_path(args.out, battery, ref)
    if not path.exists():
        fail("scorecard", f"no card {path}; make it with `racf scorecard --defence {ref}` (same --out, --quick)")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as err:
        fail("scorecard", f"{path} is not a card ({err})")


def _scorecard(args: argparse.Namespace) -> int:
    from racf.experiments.scorecard.report import compare_markdown, strict_json, write_scorecard
    from racf.plugins import ATTACKS, ESTIMATORS

    battery = _battery(args.battery)
    if args.target is not None:
        try:
            battery = battery.in_scenario(args.target, plain_values("scorecard", "--scenario-param",
                                                                     args.scenario_param))
        except ValueError as err:
            fail("scorecard", str(err))
    elif args.scenario_param:
        fail("scorecard", "--scenario-param sets a parameter of --target's scenario: give --target too")
    name = battery.name + ("-quick" if args.quick else "")
    if args.compare:
        print(compare_markdown(*(_load_card(args, ref, name) for ref in args.compare)))
        return 0
    if args.workers < 1:
        fail("scorecard", "--workers must be >= 1")
    if args.attack is not None:
        if args.attack not in ATTACKS:
            fail("scorecard", f"unknown attack {args.attack!r}; registered: {', '.join(ATTACKS)}")
        return _attack_card(args, battery)
    unknown = [d for d in args.defence if d not in ESTIMATORS]
    if unknown:
        fail("scorecard", f"unknown defence(s) {unknown}; registered: {', '.join(ESTIMATORS)}")
    options = (estimator_options("scorecard", args.estimator_option, tuple(args.defence),
                                 args.defence[0] if len(args.defence) == 1 else None)
               if args.estimator_option else {})
    from racf.experiments.scorecard.card import run_card
    from racf.experiments.sweeps.executors import backend_session
    from racf.provenance import atomic_write

    t0 = time.perf_counter()
    dataset = _dataset(args, args.quick) if battery.offline_presets else None  # racf-5 has no offline rows
    cards = []
    with backend_session(args.backend, args.workers, args.address):
        for defence in args.defence:
            try:
                card = run_card(defence, battery, args.out, quick=args.quick, dataset=dataset, backend=args.backend,
                                workers=args.workers, address=args.address, progress=not args.json,
                                options=options.get(defence), service=service_params(args, "scorecard"))
            except ValueError as err:
                fail("scorecard", str(err))
            path = _card_path(args.out, name, defence)
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(path, strict_json(card))
            cards.append(card)
    paths = write_scorecard(cards, args.out)
    if args.json:
        print(strict_json({"cards": cards}))
        return 0
    print(paths["md"].read_text())
    for card in cards:
        print(f"{card['defence']}: {card['timing']['wall_s']:.0f} s")
    print(f"wall time {time.perf_counter() - t0:.0f} s; {', '.join(str(p) for p in paths.values())}")
    return 0


def _attack_card(args: argparse.Namespace, battery) -> int:
    from racf.experiments.scorecard.attack_card import attack_card_markdown, run_attack_card
    from racf.experiments.scorecard.report import strict_json
    from racf.provenance import atomic_write

    try:
        card = run_attack_card(args.attack, args.out, quick=args.quick, backend=args.backend, workers=args.workers,
                               address=args.address, progress=not args.json)
    except ValueError as err:
        fail("scorecard", str(err))
    text = attack_card_markdown(card)
    out = args.out / "attacks" / battery.name
    out.mkdir(parents=True, exist_ok=True)
    atomic_write(out / f"{args.attack}.json", strict_json(card))
    atomic_write(out / f"{args.attack}.md", text)
    print(strict_json(card) if args.json else text)
    return 0
