"""A served defence that lies in range at the stop sign (issue 78): the three lies the protocol's check
cannot see (``IN_RANGE_LIES``: always 4 m, the truth + 3 m, nothing stands; the ids kept), each over the
four signs and five seeds, the car's onboard ODCA beside the served answer, alone and under the
supervisor. Prints one JSON object (stopped in N of N, the served answers outvoted):

    python -m tests.experiments.link.served_lies > served-lies.json
    python -m racf.experiments.pages.results_store served-lies served-lies.json \\
        --command "python -m tests.experiments.link.served_lies"
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace

from racf.experiments.episode import TrialSpec, run_trial
from racf.stats import wilson_interval
from tests.experiments.link.fake_service import IN_RANGE_LIES, FakeService

SIGNS, SEEDS = (0, 1, 2, 3), range(5)


def main() -> int:
    rows = []
    for lie in IN_RANGE_LIES:
        for supervisor in (False, True):
            stopped = outvoted = lies = invalid = fallback = 0
            for sign in SIGNS:
                for seed in SEEDS:
                    with FakeService(lie, honest=30) as fake:
                        spec = TrialSpec("clean+odca", sign, 1.0, seed, supervisor=supervisor,
                                         estimator_endpoint=fake.endpoint, estimator_timeout_ms=5000.0)
                        result, _ = run_trial(spec)
                        lies += fake.lies
                    row = result.to_dict()
                    stopped += bool(row["success"])
                    outvoted += int(row["service_outvoted"])
                    invalid += int(row["service_invalid"])
                    fallback += int(row["service_fallback_steps"])
            n = len(SIGNS) * len(SEEDS)
            lo, hi = wilson_interval(stopped, n)
            rows.append({"lie": lie, "supervisor": supervisor, "n": n, "stopped": stopped, "scr": stopped / n,
                         "scr_ci": [lo, hi], "lies": lies, "outvoted_steps": outvoted, "invalid": invalid,
                         "fallback_steps": fallback})
            print(json.dumps(rows[-1]), file=sys.stderr)
    print(json.dumps({"rows": rows, "speed_mps": 1.0, "signs": list(SIGNS), "seeds": list(SEEDS)}, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
