"""The command line's index: every command's flat name, the module that declares it and its one
line of help. ``racf`` imports only the module of the command it runs (``racf --help`` and
``racf --version`` import none), so a command answers without waiting for what another needs.

This table is made from the modules themselves (:func:`index`): tests/experiments/cli/test_commands.py
fails when it is stale, and ``python -m racf.experiments.cli.commands`` prints it anew.
"""

from __future__ import annotations

__all__ = ["COMMANDS", "MODULES", "index"]

#: The modules that declare commands, in the order ``racf --help`` lists their commands.
MODULES = ("view", "trials", "sweep", "scorecard", "board", "falsify", "data", "odca", "onboard", "detector", "bench",
           "bags", "serve", "stress")

#: flat command name -> (its module, its one line of help).
COMMANDS: dict[str, tuple[str, str | None]] = {
    "snapshot": ("view", "top view of the map and the car's camera, depth and LiDAR at a pose (PNGs)"),
    "demo": ("view", "the story at one stop sign: clean, patch attack, attack + ODCA; a table, three "
                     "rerun recordings and a PNG of the distance traces"),
    "moment": ("view", "a picture of an episode at the moment that matters: the camera and the depth "
                       "when the attack acts and the defence answers, and the distances over the "
                       "approach"),
    "view": ("view", "open a rerun recording (.rrd) in the rerun viewer"),
    "trial": ("trials", "one closed-loop stop-sign trial: per-step log (Parquet) and result row"),
    "trials": ("trials", "a batch of trials over the four signs and speeds 1.0/1.5/2.0 m/s: SCR, "
                         "latency"),
    "attack-study": ("trials", "no-defence patch attack tables: persistence, coverage, strong regime"),
    "list": ("trials", "the registered attacks, estimators (defences), detectors, scenarios (with "
                       "their parameters) and metrics (with their fields), plug-ins included"),
    "sweep": ("sweep", "a Monte Carlo attack sweep from a TOML spec or flags (grid or random draws) "
                       "on a local process pool or Ray; resumes; summary and SCR plots"),
    "scorecard": ("scorecard", "rate defences (built-in or plug-in) or an attack on the standard "
                               "battery: closed loop, drives, detection, offline and cost; one card "
                               "each"),
    "board-check": ("board", "whether cards may go on the leaderboard: full battery, full N, measured"
                             " on a committed tree"),
    "board-verify": ("board", "measure a card again: its summaries from its episodes, a sample of "
                              "episodes re-run to the bit"),
    "board-submit": ("board", "put a verified card beside racf's own: writes its submission file"),
    "falsify": ("falsify", "search the attack and scenario space for a defence's worst case (Optuna "
                           "TPE, CMA-ES, random) on the stop rule's STL robustness"),
    "replay-case": ("falsify", "rerun saved counterexamples (a case file or a folder of them): on the"
                               " same code to the bit; with --defence, against another defence"),
    "collect": ("data", "record the multi-sensor dataset of drives (Parquet, splits, card); resumes"),
    "pretrain-prior": ("odca", "pretrain the small Chronos-2 prior on synthetic series (writes a "
                               "model card)"),
    "train": ("odca", "train the ODCA delta head, alignment and gate on the dataset's train split"),
    "evaluate": ("odca", "score an ODCA checkpoint against raw depth on a dataset's test split "
                         "(weak/mid/strong presets, clean pass-through)"),
    "odca-latency": ("odca", "per-step latency of the online ODCA module (median, p99)"),
    "export-odca": ("onboard", "export ODCA's prior and head to ONNX for onnxruntime on the car (the "
                               "gate runs as it is, from odca.json)"),
    "bench-odca-onboard": ("onboard", "ODCA exported (onnxruntime) against PyTorch on the offline "
                                      "benchmark's test series: largest difference, latencies"),
    "detector-data": ("detector", "render the learned detector's views with ground-truth sign masks "
                                  "(training and held-out splits; seeded, resumes)"),
    "train-detector": ("detector", "train the stop-sign segmenter on the CPU (renders the views first"
                                   " if missing); writes a checkpoint"),
    "train-vehicle-detector": ("detector", "render views of a QCar 2 ahead and train the vehicle "
                                           "segmenter on the CPU (about 5 min); writes a checkpoint"),
    "optimise-patch": ("detector", "optimise an adversarial sticker against the learned segmenter "
                                   "(EOT over rendered views, differentiable warp); writes a PNG"),
    "bench-patch": ("detector", "the sticker printed on the sign in the scene vs the image-space "
                                "occluder, on both detectors: recall on fresh views (transfer report)"),
    "bench-sim": ("bench", "simulator steps per second and real-time factor at 50 Hz"),
    "bench-offline": ("bench", "the offline repair benchmark: every registered estimator (raw, EKF, "
                               "ODCA, plug-ins) beside the LiDAR reference and the forecasters "
                               "(Chronos-2, SOFTS, NHITS, DLinear, NLinear) on both splits and "
                               "presets (tables, figures, results.json)"),
    "bench-loop": ("bench", "closed-loop throughput: real-time factor on one core (clean, attack + "
                            "ODCA), sweep episodes per minute with 1 / 2 workers and on Ray"),
    "bench-guard": ("bench", "the speed guard: the closed loop's step cost over bare physics, in one "
                             "run; --check fails when it is more than 15 %% above the stored one"),
    "bench-paired": ("bench", "this checkout's closed loop against another checkout's, timed in "
                              "alternation on one core: ms a step of each and their ratio"),
    "bench-detector": ("bench", "stop-sign detectors side by side: recall and false-positive frames "
                                "on held-out views and approach drives, time per frame on one core"),
    "bench-poses": ("bench", "stop-sign detectors' recall over the poses real signs stand in: turned "
                             "about the pole and leaned back, at the approach distances"),
    "bench-radio": ("bench", "what checking the car ahead's signed broadcast costs: Ed25519 "
                             "verification per message on one core (p50, p99) against the 20 ms "
                             "period"),
    "bench-traffic": ("bench", "perception under cross-traffic: a car between the ego car and the "
                               "sign, one crossing behind it, a red car in view; each paired with the"
                               " same clean approach on the empty map"),
    "bench-bags": ("bags", "the cost of exporting a drive as a bag and replaying it, per simulated "
                           "second, on this process's core (the goal: each <= 2)"),
    "export-bag": ("bags", "run an episode (racf trial's flags) and write it as a ROS 2 bag (MCAP) on"
                           " Quanser's QCar 2 topics, with racf's signals under /racf/"),
    "replay-bag": ("bags", "run the car's software (perception, tracker, localisation, defence, "
                           "braker) on a recorded bag, with no simulator: the step log and a rerun "
                           "recording"),
    "bag-info": ("bags", "a bag's topics, types, counts, rates and duration"),
    "serve": ("serve", "serve defences (estimators) to cars over ZeroMQ: trials, sweeps and "
                       "scorecards reach them with --estimator-endpoint; `racf serve keys DIR` makes "
                       "CurveZMQ keys"),
    "bench-service": ("serve", "the defence service's round trip per step on real samples, beside the"
                               " in-process cost and the paper's 49 ms cycle"),
    "bench-service-stress": ("stress", "racf serve under fuzzed requests, many connections and cars "
                                       "at the control rate: alive, every answer, memory held"),
    "bench-service-probes": ("stress", "an attacker's probes of racf serve, each with its number: "
                                       "half-sent frames, checkpoint spellings, one host's many "
                                       "addresses, keep-alives that do no work"),
}


def index() -> dict[str, tuple[str, str | None]]:
    """The table as the modules declare it now (imports every module: for the test and for
    regenerating the table, never on the command line's way)."""
    import argparse
    from importlib import import_module

    out = {}
    for name in MODULES:
        parser = argparse.ArgumentParser()
        sub = parser.add_subparsers()
        import_module(f"racf.experiments.cli.{name}").register(sub)
        out |= {action.dest: (name, action.help) for action in sub._choices_actions}
    return out


def _source(table: dict[str, tuple[str, str | None]]) -> str:
    """The table as this module's source holds it (wrapped at 120 columns)."""
    import json
    import textwrap

    lines = []
    for flat, (module, text) in table.items():
        head = f"    {json.dumps(flat)}: ({json.dumps(module)}, "
        if text is None:
            lines.append(f"{head}None),")
            continue
        parts = textwrap.wrap(text, 100 - len(head), drop_whitespace=False) or [""]
        lines.append(head + json.dumps(parts[0]) + ("" if len(parts) > 1 else "),"))
        lines += [" " * len(head) + json.dumps(part) + ("),"  if i == len(parts) - 2 else "")
                  for i, part in enumerate(parts[1:])]
    return "\n".join(lines)


if __name__ == "__main__":
    print(_source(index()))
