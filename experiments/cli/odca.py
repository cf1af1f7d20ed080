"""``racf odca pretrain-prior``, ``racf odca train``, ``racf odca evaluate`` and ``racf bench odca-latency``: ODCA's checkpoints."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from racf.experiments.cli.common import count, output_dir

__all__ = ["register"]

_SPLITS = ("by_series", "leave_target_out")


def register(sub: argparse._SubParsersAction) -> None:
    pp = sub.add_parser("pretrain-prior",
                        help="pretrain the small Chronos-2 prior on synthetic series (writes a model card)")
    pp.add_argument("--out", type=output_dir, default=Path("outputs/chronos2-prior"),
                    help="checkpoint folder (default outputs/chronos2-prior; name "
                         "assets/checkpoints/chronos2-racf-tiny to replace the shipped prior)")
    pp.add_argument("--steps", type=count, default=3000, help="training steps (default 3000)")
    pp.add_argument("--series", type=count, default=6000, help="synthetic training series (default 6000)")
    pp.add_argument("--seed", type=int, default=0)
    pp.add_argument("--dataset", type=Path, default=Path("data/qcar2"),
                    help="dataset whose test-split d_clean series are scored too, if it exists")
    pp.set_defaults(handler=_pretrain_prior)

    tr = sub.add_parser("train", help="train the ODCA delta head, alignment and gate on the dataset's train split")
    tr.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    tr.add_argument("--split", choices=_SPLITS, default="by_series",
                    help="split scheme to train on and score (default by_series)")
    tr.add_argument("--out", type=output_dir, default=Path("outputs/odca-head"),
                    help="checkpoint folder (default outputs/odca-head; name assets/checkpoints/odca-head to replace "
                         "the shipped head)")
    tr.add_argument("--epochs", type=count, default=800)
    tr.add_argument("--seed", type=int, default=0)
    tr.set_defaults(handler=_train)

    ev = sub.add_parser("evaluate", help="score an ODCA checkpoint against raw depth on a dataset's test split "
                                         "(weak/mid/strong presets, clean pass-through)")
    ev.add_argument("--checkpoint", type=Path, default=None, help="ODCA folder (default: the shipped head)")
    ev.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    ev.add_argument("--split", choices=_SPLITS, default="by_series",
                    help="split scheme whose test series are scored (default by_series)")
    ev.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    ev.set_defaults(handler=_evaluate)

    ol = sub.add_parser("odca-latency", help="per-step latency of the online ODCA module (median, p99)")
    ol.add_argument("--steps", type=count, default=2000)
    ol.add_argument("--threads", type=count, default=1, help="torch threads (default 1)")
    ol.add_argument("--json", action="store_true", help="print one JSON object")
    ol.set_defaults(handler=_odca_latency)


def _pretrain_prior(args: argparse.Namespace) -> int:
    from racf.experiments.offline.training import pretrain_checkpoint
    from racf.odca.prior import SHIPPED_PRIOR

    if not (args.dataset / "dataset.parquet").exists():
        print(f"no dataset at {args.dataset}: scoring on synthetic series only", file=sys.stderr)
    meta = pretrain_checkpoint(args.out, steps=args.steps, series=args.series, seed=args.seed, dataset=args.dataset)
    if args.out.resolve() != SHIPPED_PRIOR.resolve():
        print(f"wrote {args.out}; the shipped prior ({SHIPPED_PRIOR}) is unchanged", file=sys.stderr)
    print(json.dumps(meta, indent=1))
    return 0


def _train(args: argparse.Namespace) -> int:
    from racf.experiments.offline.training import train_checkpoint
    from racf.odca.online import SHIPPED_HEAD

    report = train_checkpoint(args.dataset, args.out, split=args.split, epochs=args.epochs, seed=args.seed)
    print(json.dumps(report, indent=1))
    print(train_table(report))
    shipped = " (the shipped head)" if args.out.resolve() == SHIPPED_HEAD.resolve() else \
        f"; the shipped head ({SHIPPED_HEAD}) is unchanged"
    print(f"head parameters: {report['head_parameters']}; checkpoint: {args.out}{shipped}")
    return 0


def _evaluate(args: argparse.Namespace) -> int:
    from racf.experiments.data.dataset import load_dataset
    from racf.odca.online import ODCA
    from racf.odca.train import evaluate

    report = evaluate(ODCA.load(args.checkpoint), load_dataset(args.dataset, split=args.split))
    print(json.dumps(report) if args.json else train_table(report))
    return 0


def _odca_latency(args: argparse.Namespace) -> int:
    from racf.experiments.bench.odca_latency import odca_latency

    r = odca_latency(steps=args.steps, threads=args.threads)
    if args.json:
        print(json.dumps(r))
    else:
        print(f"ODCA step on the CPU ({r['threads']} thread, prior every {r['refresh_steps']} steps): "
              f"median {r['median_ms']:.3f} ms, p99 {r['p99_ms']:.3f} ms, max {r['max_ms']:.2f} ms over {r['steps']} "
              f"steps; p99 / 2 ms goal = {r['p99_ms'] / 2:.2f}; paper's offboard loop 49 ms")
    return 0


def train_table(report: dict) -> str:
    """The test-split table of a training report: raw depth against ODCA per preset, and clean pass-through."""
    def f(v):
        return "-" if v is None else f"{v:.4f}"

    lines = [f"test split ({report['split']}); RMSE/MAE in m against d_clean (all, moving) and against d_true",
             f"{'preset':<8}{'N':>7}{'N moving':>9}{'RMSE raw':>10}{'RMSE ODCA':>11}{'moving raw':>12}"
             f"{'moving ODCA':>13}{'MAE raw':>9}{'MAE ODCA':>10}{'vs true raw':>13}{'vs true ODCA':>14}"]
    for preset, r in report["test"].items():
        lines.append(f"{preset:<8}{r['n']:>7}{r['n_moving']:>9}{f(r['rmse_raw']):>10}{f(r['rmse']):>11}"
                     f"{f(r['rmse_moving_raw']):>12}{f(r['rmse_moving']):>13}{f(r['mae_raw']):>9}{f(r['mae']):>10}"
                     f"{f(r['rmse_true_raw']):>13}{f(r['rmse_true']):>14}")
    p = report["clean_pass_through"]
    lines.append(f"clean pass-through (input = d_clean): unchanged on {p['unchanged_share']:.2%} of {p['n_depth']} "
                 f"steps with depth ({p['unchanged_share_both_present']:.2%} of {p['n_both_present']} with the LiDAR "
                 f"too); RMSE vs input {1000 * p['rmse_vs_input']:.2f} mm; changed > 1 cm on "
                 f"{p['changed_over_1cm_share']:.2%}")
    return "\n".join(lines)
