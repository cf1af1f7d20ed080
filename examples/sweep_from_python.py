"""A sweep from Python over the two example plug-ins: the CUSUM defence (an installed package)
against the depth-scaling attack (one file), beside racf's own ODCA and raw depth.

    pip install examples/racf-cusum
    python examples/sweep_from_python.py --out outputs/examples-sweep

Prints the stop compliance rate (SCR) of each setting. A rerun reuses every finished episode;
after an edit to either plug-in, the episodes that use it run again (their ids hash its source).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from racf.experiments.sweeps.run import run_sweep
from racf.experiments.sweeps.spec import parse_spec
from racf.plugins import ESTIMATORS, load_plugin_file

HERE = Path(__file__).resolve().parent

SPEC = """
name = "examples"
mode = "grid"
seed = 0

[space]
attack = ["none", "depth_scale"]
estimator = ["raw", "odca", "lidar_cusum"]
rho = [1.0]
t_atk = [2.0]
speed = [1.5]
sign = {signs}

[params.depth_scale]
scale = [1.6]

[estimators.lidar_cusum]
h_m = 0.25
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("outputs/examples-sweep"), help="results folder")
    parser.add_argument("--signs", type=int, nargs="+", default=[0, 1, 2, 3], help="stop signs 0-3 (default all)")
    parser.add_argument("--workers", type=int, default=2, help="parallel episodes (default 2)")
    args = parser.parse_args(argv)
    if "lidar_cusum" not in ESTIMATORS:
        parser.error("the example defence is not installed: pip install examples/racf-cusum")
    load_plugin_file(HERE / "depth_scale_attack.py")  # the one-file attack; worker processes load it too
    text = SPEC.format(signs=json.dumps(args.signs))
    summary = run_sweep(parse_spec(text, "examples"), text, args.out, workers=args.workers, progress=False)
    print(json.dumps(summary["scr"], indent=1, sort_keys=True))
    print(f"{summary['n']} episodes ({summary['done']} run, {summary['reused']} reused); results in {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
