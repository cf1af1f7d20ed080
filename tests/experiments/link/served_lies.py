"""A served defence that lies in range at the stop sign (issue 78): the three lies the protocol's check
cannot see (``IN_RANGE_LIES``: always 4 m, the truth + 3 m, nothing stands; the ids kept), each over the
four signs and five seeds, the car's onboard ODCA beside the served answer, alone and under the
supervisor; then racf-link's plain-link spoof (a man in the middle answering 5 m for a real ODCA
service under the strong patch, racf-link's row: 60 episodes, the car's fallback raw depth), alone and
under the supervisor. Prints one JSON object (stopped in N of N, the served answers outvoted):

    python -m tests.experiments.link.served_lies > served-lies.json
    python -m racf.experiments.pages.results_store served-lies served-lies.json \\
        --command "python -m tests.experiments.link.served_lies"
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.scorecard.battery import PAPER_LOOP_HZ
from racf.experiments.scorecard.battery_types import CAR_DETECTOR
from racf.experiments.sweeps.batches import batch_specs
from racf.experiments.sweeps.service_process import service_process
from racf.stats import wilson_interval
from tests.experiments.link.fake_service import IN_RANGE_LIES, FakeService

SIGNS, SEEDS = (0, 1, 2, 3), range(5)
#: racf-link's plain-link spoof row (its attack: every answer in the window says the sign is 5 m away),
#: at the issue's N.
LINK_SPOOF, LINK_SPOOF_N = {"link_spoof": {"distance_m": 5.0}}, 60


def _row(lie: str, supervisor: bool, results: list[dict], lies: int | None) -> dict:
    n, stopped = len(results), sum(bool(r["success"]) for r in results)
    lo, hi = wilson_interval(stopped, n)
    return {"lie": lie, "supervisor": supervisor, "n": n, "stopped": stopped, "scr": stopped / n, "scr_ci": [lo, hi],
            "lies": lies, "outvoted_steps": sum(int(r["service_outvoted"]) for r in results),
            "invalid": sum(int(r["service_invalid"]) for r in results),
            "fallback_steps": sum(int(r["service_fallback_steps"]) for r in results)}


def link_spoof_rows() -> list[dict]:
    """racf-link's plain-link spoof, alone and supervised, on the same episodes: a real ODCA service."""
    rows = []
    with service_process("odca") as (endpoint, _):
        for supervisor in (False, True):
            specs = batch_specs("attack+link_spoof+odca", LINK_SPOOF_N, detector=CAR_DETECTOR, control_hz=PAPER_LOOP_HZ,
                                estimator_endpoint=endpoint, attack_params=LINK_SPOOF, estimator_fallback="raw",
                                supervisor=supervisor)
            results = [run_trial(spec)[0].to_dict() for spec in specs]
            # The man in the middle's answers are not counted on the car's side: no count of lies.
            rows.append(_row("link_spoof (5 m, plain link)", supervisor, results, None))
            print(json.dumps(rows[-1]), file=sys.stderr)
    return rows


def main() -> int:
    rows = []
    for lie in IN_RANGE_LIES:
        for supervisor in (False, True):
            results, lies = [], 0
            for sign in SIGNS:
                for seed in SEEDS:
                    with FakeService(lie, honest=30) as fake:
                        spec = TrialSpec("clean+odca", sign, 1.0, seed, supervisor=supervisor,
                                         estimator_endpoint=fake.endpoint, estimator_timeout_ms=5000.0)
                        results.append(run_trial(spec)[0].to_dict())
                        lies += fake.lies
            rows.append(_row(lie, supervisor, results, lies))
            print(json.dumps(rows[-1]), file=sys.stderr)
    print(json.dumps({"rows": rows, "link_spoof": link_spoof_rows(), "speed_mps": 1.0, "signs": list(SIGNS),
                      "seeds": list(SEEDS)}, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
