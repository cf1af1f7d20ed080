"""``racf odca export``: ODCA as ONNX files for the car; ``racf bench odca-onboard``: the exported
ODCA against the PyTorch path, step by step, with both latencies beside the control period."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from racf.experiments.cli.common import fail

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser("export-odca", help="export ODCA's prior and head to ONNX for onnxruntime on the car "
                                           "(the gate runs as it is, from odca.json)",
                       description="Writes OUT/prior.onnx, OUT/head.onnx, the checkpoint's odca.json and head.npz, "
                                   "and OUT/export.json. Episodes run it with --estimator-option runtime=onnx "
                                   "(and checkpoint=OUT for another than the shipped export).")
    e.add_argument("out", type=Path, metavar="OUT", help="the folder to write (new or empty)")
    e.add_argument("--checkpoint", type=Path, default=None, help="the ODCA folder to export (default: the shipped one)")
    e.set_defaults(handler=_export)

    b = sub.add_parser("bench-odca-onboard", help="ODCA exported (onnxruntime) against PyTorch on the offline "
                                                  "benchmark's test series: largest difference, latencies",
                       description="Steps the PyTorch ODCA and the exported one through the dataset's by-series "
                                   "test split, clean and under each corruption preset, on one thread: the largest "
                                   "difference in d_fused, the steps where the gate chose another source, and each "
                                   "path's p50/p99/max step time against the 20 ms control period.")
    b.add_argument("--dataset", type=Path, default=Path("data/qcar2"), help="dataset folder (racf collect)")
    b.add_argument("--export", type=Path, default=None, help="the exported folder (default: the shipped export)")
    b.add_argument("--json", action="store_true", help="print one JSON object")
    b.set_defaults(handler=_bench)


def _export(args: argparse.Namespace) -> int:
    from racf.odca.onnx_export import export_onnx

    manifest = export_onnx(args.out, args.checkpoint)
    print(f"wrote {args.out}: prior.onnx ({manifest['prior']['n_parameters']:,} frozen parameters, a window of "
          f"{manifest['prior']['context_length']}), head.onnx ({manifest['head']['n_parameters']} parameters), "
          f"odca.json, head.npz, export.json")
    print(f"run it in an episode with --estimator odca --estimator-option runtime=onnx "
          f"--estimator-option checkpoint={args.out}; compare it with `racf bench odca-onboard --export {args.out}`")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from racf.experiments.bench.odca_onboard import compare_onboard

    if not (args.dataset / "dataset.parquet").exists():
        fail("bench odca-onboard", f"no dataset at {args.dataset}; make one with `racf collect --out {args.dataset}`")
    with tqdm(desc="odca onboard", unit="step", disable=args.json) as bar:
        result = compare_onboard(args.dataset, args.export, progress=bar.update)
    if args.json:
        print(json.dumps(result, indent=2, allow_nan=False))
        return 0
    print(f"ODCA exported (onnxruntime) against PyTorch on {result['series']} test runs, {result['steps']} steps "
          f"({result['dataset']}, by-series test split)")
    print(f"largest |d_fused difference|: {result['max_abs_diff_m']:.2e} m (by preset: "
          + ", ".join(f"{k} {v:.1e}" for k, v in result["max_abs_diff_m_by_preset"].items())
          + f"); steps where the gate chose another source: {result['source_changes']}")
    print(f"{'one thread':<22}{'p50 ms':>9}{'p99 ms':>9}{'max ms':>9}   steps over the {result['control_period_ms']:g} ms "
          f"period")
    for name, row in result["latency"].items():
        label = "PyTorch" if name == "torch" else "onnxruntime (onboard)"
        print(f"{label:<22}{row['p50_ms']:>9.3f}{row['p99_ms']:>9.3f}{row['max_ms']:>9.2f}   {row['over_period']}")
    return 0
