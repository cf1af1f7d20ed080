"""``racf collect``: the multi-sensor dataset of drives."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from racf.experiments.cli.common import backend_flags, count, output_dir, sensor_flags

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    co = sub.add_parser("collect", help="record the multi-sensor dataset of drives (Parquet, splits, card); resumes")
    co.add_argument("--out", type=output_dir, default=Path("data/qcar2"), help="dataset folder (default data/qcar2)")
    co.add_argument("--drives", type=count, default=None,
                    help="drives of 20-60 s, each meeting >= 2 targets (default 36: > 67,821 samples)")
    co.add_argument("--seed", type=int, default=0, help="collection seed (drive seeds and the splits)")
    sensor_flags(co)
    backend_flags(co)
    co.add_argument("--summary", action="store_true", help="print the summary as one JSON object")
    co.set_defaults(handler=_collect)


def _collect(args: argparse.Namespace) -> int:
    from racf.experiments.data.dataset import DEFAULT_DRIVES, collect, load_dataset, summarize_dataset

    # The bar is on stderr; --summary JSON stays alone on stdout.
    path = collect(args.out, drives=args.drives or DEFAULT_DRIVES, seed=args.seed, workers=args.workers,
                   progress=True, backend=args.backend, address=args.address, sensor_profile=args.sensor_profile,
                   sign_geometry=args.sign_geometry)
    ds = load_dataset(args.out)
    summary = summarize_dataset(ds.frame, ds.splits)
    if args.summary:
        print(json.dumps(summary))
    else:
        print(json.dumps(summary, indent=1))
        print(f"dataset: {path}; card: {args.out / 'dataset_card.md'}; plot: {args.out / 'series.png'}")
    return 0
