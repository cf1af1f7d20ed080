"""A6 measured: how far the car's own distance along its route lies from the truth's, on supervised
stop-sign approaches (the room the static supervisor's stop rule reads).

Each step the car moves, both poses (the car's estimate and the body's) are projected on the sign's
route; the difference of their arclengths is the error of the car's route distance to any line ahead.

    python -m tests.experiments.car.supervisor.route_error [--seeds 15] [--json FILE]

prints, per sign, the largest error either way (N episodes, each sign at 1.0, 1.5 and 2.0 m/s in turn).
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

#: The episodes' seeds: episode k of a sign is seed BASE_SEED + k (the same episodes anywhere).
BASE_SEED = 1000
SPEEDS = (1.0, 1.5, 2.0)


def route_errors(sign: int, speed: float, seed: int) -> np.ndarray:
    """The car's route position less the truth's, m, at each step the car moves (positive: the car
    thinks itself farther along, with less room than it has)."""
    return _errors(sign, _episode(sign, speed, seed)[1])


def _episode(sign: int, speed: float, seed: int):
    from racf.experiments.episode import TrialSpec, run_trial

    return run_trial(TrialSpec("clean+odca", sign, speed, seed, supervisor=True))


def _errors(sign: int, log) -> np.ndarray:
    from racf.sim.world.stop_signs import stop_signs

    path = stop_signs()[sign].path
    moving = log["speed"].to_numpy(float) > 0.05
    errors, hint = [], None
    for x, y, xe, ye in log.loc[moving, ["x", "y", "x_est", "y_est"]].to_numpy(float):
        truth, _ = path.project(np.array([x, y]), s_hint=hint)
        own, _ = path.project(np.array([xe, ye]), s_hint=truth)
        hint = truth
        errors.append(own - truth)
    return np.asarray(errors)


def measure(seeds: int) -> list[dict]:
    rows = []
    for sign in range(4):
        for k in range(seeds):
            speed = SPEEDS[k % len(SPEEDS)]
            row, log = _episode(sign, speed, BASE_SEED + k)
            err = _errors(sign, log)
            rows.append({"sign": sign, "speed": speed, "seed": BASE_SEED + k, "steps": int(err.size),
                         "ahead_max_m": float(err.max()), "behind_max_m": float(-err.min()),
                         "success": bool(row.success), "stop_distance_m": float(row.stop_distance_m)})
            print(f"sign {sign} at {speed} m/s, seed {BASE_SEED + k}: {rows[-1]['behind_max_m']:.3f} m behind, "
                  f"{rows[-1]['ahead_max_m']:.3f} m ahead at most", file=sys.stderr, flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=15, help="episodes per sign (default 15)")
    parser.add_argument("--json", help="write the rows and the summary here")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error(f"--seeds must be at least 1, got {args.seeds}")
    rows = measure(args.seeds)
    summary = {"episodes": len(rows), "behind_max_m": max(r["behind_max_m"] for r in rows),
               "ahead_max_m": max(r["ahead_max_m"] for r in rows),
               "stopped_in_band": sum(r["success"] for r in rows)}
    print(f"N {summary['episodes']} episodes: the car's route position off the truth by at most "
          f"{summary['behind_max_m']:.3f} m behind (more room than it has) and {summary['ahead_max_m']:.3f} m ahead; "
          f"{summary['stopped_in_band']} of {len(rows)} stopped for the sign")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"summary": summary, "rows": rows}, f, indent=1, allow_nan=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
