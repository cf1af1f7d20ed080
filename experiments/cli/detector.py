"""The learned detector and its adversarial patch: ``detector-data``, ``train-detector``,
``optimise-patch`` and ``bench-patch``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from racf.experiments.cli.common import count, fail, fmt_ci, output_dir

__all__ = ["register"]


def _share(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 0.6], got {text!r}") from None
    if not 0.0 < value <= 0.6:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 0.6], got {text!r}")
    return value


def _position(text: str) -> tuple[float, float] | str:
    from racf.sim.world.sign_patch import POSITIONS

    if text in POSITIONS:
        return text
    try:
        right, up = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected RIGHT,UP (across-flats units, each in [-0.5, 0.5]) or one of "
                                         f"{', '.join(POSITIONS)}, got {text!r}") from None
    return right, up


def register(sub: argparse._SubParsersAction) -> None:
    dd = sub.add_parser("detector-data", help="render the learned detector's views with ground-truth sign masks "
                                              "(training and held-out splits; seeded, resumes)")
    dd.add_argument("--out", type=output_dir, default=Path("data/detector"), help="folder (default data/detector)")
    dd.add_argument("--seed", type=int, default=0, help="seed of the training split (held-out: seed + 1000003)")
    dd.add_argument("--train", type=count, default=None, help="training views (default: the default dataset's, 10000)")
    dd.add_argument("--heldout", type=count, default=None,
                    help="held-out views (default: the default dataset's, 2000)")
    dd.set_defaults(handler=_detector_data)

    td = sub.add_parser("train-detector", help="train the stop-sign segmenter on the CPU (renders the views first "
                                               "if missing); writes a checkpoint")
    td.add_argument("--data", type=Path, default=Path("data/detector"), help="views folder (racf detector data)")
    td.add_argument("--out", type=output_dir, default=Path("outputs/sign-segmenter"),
                    help="checkpoint folder (default outputs/sign-segmenter; the shipped one is "
                         "assets/checkpoints/sign-segmenter)")
    td.add_argument("--seed", type=int, default=0, help="initialisation, batch order and augmentation seed")
    td.add_argument("--epochs", type=count, default=None, help="passes over the training views (default 30)")
    td.add_argument("--threads", type=count, default=2, help="torch threads (default 2)")
    td.add_argument("--json", action="store_true", help="print the training report as one JSON object")
    td.set_defaults(handler=_train_detector)

    tv = sub.add_parser("train-vehicle-detector", help="render views of a QCar 2 ahead and train the vehicle segmenter "
                                                       "on the CPU (about 5 min); writes a checkpoint")
    tv.add_argument("--out", type=output_dir, default=Path("outputs/vehicle-segmenter"),
                    help="checkpoint folder (default outputs/vehicle-segmenter; the shipped one is "
                         "assets/checkpoints/vehicle-segmenter)")
    tv.add_argument("--seed", type=int, default=0, help="views, initialisation and batch order seed")
    tv.add_argument("--train", type=count, default=None, help="training views (default 4000)")
    tv.add_argument("--heldout", type=count, default=None, help="held-out views (default 800)")
    tv.add_argument("--epochs", type=count, default=None, help="passes over the training views (default 12)")
    tv.add_argument("--json", action="store_true", help="print the training report as one JSON object")
    tv.set_defaults(handler=_train_vehicle)

    op = sub.add_parser("optimise-patch", help="optimise an adversarial sticker against the learned segmenter "
                                               "(EOT over rendered views, differentiable warp); writes a PNG")
    op.add_argument("--data", type=Path, default=Path("data/detector"), help="views folder (racf detector data)")
    op.add_argument("--checkpoint", type=Path, default=None, help="segmenter checkpoint (default: the shipped one)")
    op.add_argument("--out", type=output_dir, default=Path("outputs/patches"),
                    help="folder for learned.png and learned.json (default outputs/patches; the shipped one is "
                         "assets/patches)")
    op.add_argument("--seed", type=int, default=0, help="initial texture and transformation seed")
    op.add_argument("--size", type=_share, default=0.5, help="sticker area / plate area, in (0, 0.6] (default 0.5)")
    op.add_argument("--position", type=_position, default=(0.0, 0.0),
                    help="sticker centre RIGHT,UP on the plate, across-flats units (default 0,0)")
    op.add_argument("--steps", type=count, default=None, help="optimiser steps (default 600)")
    op.add_argument("--views", choices=("dataset", "approach"), default="dataset",
                    help="the expectation's views: dataset, the detector's training views (any distance and "
                         "angle; default); approach, views on the car's approaches weighted to the frames where "
                         "detection decides the stop (rendered here, no --data needed)")
    op.add_argument("--json", action="store_true", help="print the report as one JSON object")
    op.set_defaults(handler=_optimise_patch)

    bp = sub.add_parser("bench-patch", help="the sticker printed on the sign in the scene vs the image-space "
                                            "occluder, on both detectors: recall on fresh views (transfer report)")
    bp.add_argument("-n", type=count, default=400, help="views of a stop sign (default 400)")
    bp.add_argument("--texture", default="learned",
                    help="sticker: a shipped name (learned), natural, or a PNG path (default learned)")
    bp.add_argument("--size", type=_share, default=0.5, help="sticker area / plate area (default 0.5)")
    bp.add_argument("--position", type=_position, default=(0.0, 0.0),
                    help="sticker centre RIGHT,UP on the plate, across-flats units, or centre, top, bottom, left, "
                         "right: as far that way as it stays on the plate (default 0,0)")
    bp.add_argument("--views", choices=("sign", "approach"), default="sign",
                    help="where the views stand: sign, anywhere around the sign, 0.3-4 m (default); approach, on "
                         "the car's own approaches (to choose a sticker's size and place before the loop)")
    bp.add_argument("--detector", nargs="+", choices=None, default=None, metavar="NAME",
                    help="the detectors to try (default: every registered one)")
    bp.add_argument("--figure", type=Path, default=None,
                    help="also write a PNG of near views, clean and patched, with the learned detector's mask")
    bp.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    bp.set_defaults(handler=_bench_patch)


def _detector_data(args: argparse.Namespace) -> int:
    from racf.experiments.detector.dataset import DatasetSpec, load_split, make_dataset
    from racf.experiments.detector.evaluate import VIEW_KINDS

    sizes = {k: v for k, v in (("n_train", args.train), ("n_heldout", args.heldout)) if v is not None}
    try:
        spec = DatasetSpec(seed=args.seed, **sizes)
    except ValueError as err:
        fail("detector-data", str(err))
    make_dataset(spec, args.out)
    for split in ("train", "heldout"):
        d = load_split(args.out, split)
        kinds = ", ".join(f"{int((d['kind'] == k).sum())} {name}" for k, name in enumerate(VIEW_KINDS))
        print(f"{split}: {len(d['rgb'])} views ({kinds}), {int(d['mask'].any(axis=(1, 2)).sum())} with a stop "
              f"sign's face in view")
    print(f"views in {args.out}")
    return 0


def _train_detector(args: argparse.Namespace) -> int:
    from racf.experiments.detector.dataset import DatasetSpec, make_dataset
    from racf.experiments.detector.train import TrainConfig, train_segmenter

    try:
        config = TrainConfig(seed=args.seed, threads=args.threads,
                             **({"epochs": args.epochs} if args.epochs else {}))
    except ValueError as err:
        fail("train-detector", str(err))
    if not (args.data / "manifest.json").is_file():
        make_dataset(DatasetSpec(), args.data)
    _, report = train_segmenter(config, args.data, args.out, progress=not args.json)
    if args.json:
        print(json.dumps(report, allow_nan=False))
        return 0
    h = report["heldout"]
    print(f"trained {report['parameters']} parameters on {report['n_train']} views in {report['train_s'] / 60:.1f} min")
    print(f"held-out views (N = {h['n_positive']} with a sign): recall {h['recall']:.4f} {fmt_ci(*h['recall_ci'])}, "
          f"false-positive frames {h['n_fp']} / {h['n_frames']} = {100 * h['fp_rate']:.2f} %")
    print(f"checkpoint in {args.out}")
    return 0


def _train_vehicle(args: argparse.Namespace) -> int:
    from racf.experiments.detector.vehicle_train import VehicleTrainConfig, train_vehicle_segmenter

    given = {"n_train": args.train, "n_heldout": args.heldout, "epochs": args.epochs}
    try:
        config = VehicleTrainConfig(seed=args.seed, **{k: v for k, v in given.items() if v is not None})
    except ValueError as err:
        fail("train-vehicle-detector", str(err))
    _, report = train_vehicle_segmenter(config, args.out, progress=not args.json)
    if args.json:
        print(json.dumps(report, allow_nan=False))
        return 0
    h = report["heldout"]
    print(f"trained {report['parameters']} parameters on {config.n_train} views in {report['train_s'] / 60:.1f} min")
    for band, r in h["recall"].items():
        print(f"held-out cars {band} away: found {r['found']} / {r['n']}")
    fp = h["false_positive"]
    print(f"held-out frames without a car: a car found in {fp['frames']} / {fp['n']}")
    print(f"checkpoint in {args.out}")
    return 0


def _optimise_patch(args: argparse.Namespace) -> int:
    from racf.controllers.learned_detector import SHIPPED_SEGMENTER
    from racf.experiments.detector.patch_opt import PatchConfig, optimise_patch

    try:
        config = PatchConfig(seed=args.seed, size=args.size, position=args.position, views=args.views,
                             **({"steps": args.steps} if args.steps else {}))
    except ValueError as err:
        fail("optimise-patch", str(err))
    if config.views == "dataset" and not (args.data / "manifest.json").is_file():
        fail("optimise-patch", f"no views in {args.data}: render them with `racf detector data --out {args.data}`")
    try:
        _, report = optimise_patch(config, args.data, args.checkpoint or SHIPPED_SEGMENTER, args.out,
                                   progress=not args.json)
    except (FileNotFoundError, ValueError) as err:
        fail("optimise-patch", str(err))
    if args.json:
        print(json.dumps(report, allow_nan=False))
        return 0
    print(f"optimised over {report['n_views']} views in {report['optimise_s']:.0f} s: loss "
          f"{report['loss_first']:.3f} -> {report['loss_last']:.3f}")
    print(f"sticker in {args.out / 'learned.png'}; try it in the scene with `racf bench patch --texture "
          f"{args.out / 'learned.png'}`")
    return 0


def _bench_patch(args: argparse.Namespace) -> int:
    from racf.experiments.bench.patch_transfer import DISTANCE_BANDS_M, RENDERINGS, bench_patch
    from racf.experiments.detector.evaluate import band_label

    try:
        result, examples = bench_patch(args.n, args.texture, args.size, args.position, progress=not args.json,
                                       keep_examples=4 if args.figure else 0, views=args.views,
                                       **({"detectors": tuple(args.detector)} if args.detector else {}))
    except (FileNotFoundError, ValueError) as err:
        fail("bench-patch", str(err))
    if args.figure:
        from racf.experiments.viz.patch_figure import patched_sign_figure

        patched_sign_figure(examples, args.figure)
    if args.json:
        print(json.dumps(result.to_dict(), allow_nan=False))
        return 0
    any_counts = next(iter(next(iter(result.counts.values())).values()))
    print(f"sticker {args.texture!r}, {args.size:.2f} of the plate at {result.position}; {result.n_views} {args.views} views, "
          f"N = {any_counts.n_positive} with the sign resolvable")
    bands = [band_label(lo, hi) for lo, hi in DISTANCE_BANDS_M]
    print(f"{'detector':<11}{'rendering':<17}{'recall [95 % CI]':>26}" + "".join(f"{b:>14}" for b in bands))
    for det, row in result.counts.items():
        for rendering in RENDERINGS:
            c = row[rendering]
            per_band = result.by_band[det][rendering]
            print(f"{det:<11}{rendering:<17}{c.recall:>10.3f} {fmt_ci(*c.to_dict()['recall_ci']):>15}"
                  + "".join(f"{per_band[b].recall:>9.3f} N={per_band[b].n_positive:<3}"
                            if per_band[b].recall is not None else f"{'-':>14}" for b in bands))
    print("goal: physical_patch lowers the learned detector's recall to <= 0.2 (sticker <= half the plate)")
    return 0
