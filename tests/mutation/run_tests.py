"""cosmic-ray's test command for `make mutate`: the tests that mirror the mutated module, stopping at
the first failure. The mutant lies on disk, so git names the module; each module's tests are listed
fastest-killing first. Exit 0: the mutant survived; anything else: killed."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SERVICE = "tests/experiments/service"
LINK = "tests/experiments/link"
EPISODE = "tests/experiments/episode"
CAR = "tests/experiments/car"
SUP = "tests/experiments/car/supervisor"
#: How each mutant's tests run: to the first failure, the same hypothesis examples for every mutant.
PYTEST_ARGS = ["-x", "-q", "-p", "no:cacheprovider", "-p", "no:xdist", "-m", "not slow", "--hypothesis-profile=mutation"]
#: The tests that must kill a mutant of each module (every one must exist: a moved test file is an error,
#: never a mutant that survives for want of its tests).
TESTS = {
    "experiments/link/wire.py": [f"{LINK}/test_wire.py", f"{LINK}/test_remote.py", f"{SERVICE}/test_fuzz.py"],
    "experiments/link/remote.py": [f"{LINK}/test_remote.py", f"{SERVICE}/test_auth.py", f"{SERVICE}/test_server.py"],
    "experiments/link/curve.py": [f"{SERVICE}/test_auth.py"],
    "experiments/service/handler.py": [f"{SERVICE}/test_handler.py", f"{SERVICE}/test_fuzz.py",
                                       f"{SERVICE}/test_server.py", f"{SERVICE}/test_auth.py"],
    "experiments/service/sessions.py": [f"{SERVICE}/test_sessions.py", f"{SERVICE}/test_limits.py"],
    "experiments/service/server.py": [f"{SERVICE}/test_fuzz.py", f"{SERVICE}/test_auth.py",
                                      f"{SERVICE}/test_limits.py", f"{SERVICE}/test_server.py"],
    # The car's side as parts (issue 68): the stage contract, the declared targets, the report road.
    "experiments/car/stage.py": [f"{CAR}/test_stage.py", f"{CAR}/test_following_stage.py"],
    "experiments/car/following/stage.py": [f"{CAR}/test_following_stage.py", f"{CAR}/test_stage.py",
                                           "tests/experiments/scenarios/test_lead_vehicle.py"],
    "experiments/episode/record.py": [f"{EPISODE}/test_record.py", f"{CAR}/test_stage.py", f"{EPISODE}/test_preflight.py"],
    "experiments/episode/preflight.py": [f"{EPISODE}/test_preflight.py"],
    "sim/world/manager.py": ["tests/sim/world/test_targets.py", "tests/sim/attacks/test_lead_attacks.py"],
    "sim/world/qcar2_body.py": ["tests/sim/world/test_targets.py", "tests/sim/attacks/test_lead_attacks.py"],
    "experiments/episode/criteria.py": [f"{EPISODE}/test_stop_rule_criteria.py",
                                        "tests/experiments/scenarios/test_cross_traffic.py"],
    "experiments/metrics/criteria.py": ["tests/experiments/scorecard/test_battery.py",
                                        "tests/experiments/metrics/test_criteria.py"],
    "experiments/scorecard/card_format.py": ["tests/experiments/scorecard/test_battery.py",
                                             "tests/experiments/scorecard/test_headline.py"],
    # The supervisor (issue 69).
    "experiments/car/supervisor/envelope.py": [f"{SUP}/test_envelope.py", f"{SUP}/test_vehicle_supervisor.py"],
    "experiments/car/supervisor/track.py": [f"{SUP}/test_track.py", f"{SUP}/test_vouch.py",
                                            f"{SUP}/test_vehicle_supervisor.py"],
    "experiments/car/supervisor/vouch.py": [f"{SUP}/test_vouch.py", f"{SUP}/test_vehicle_supervisor.py"],
    "experiments/car/supervisor/clear.py": [f"{SUP}/test_lane_witness.py"],
    "experiments/car/supervisor/vehicle.py": [f"{SUP}/test_vehicle_supervisor.py"],
    # The guarantee at every target (issue 78).
    "experiments/car/supervisor/static.py": [f"{SUP}/test_static.py", f"{CAR}/test_assembly.py"],
    "experiments/car/supervisor/speed.py": [f"{SUP}/test_range_rate.py"],
    "controllers/speed.py": ["tests/controllers/test_speed_bound.py", "tests/controllers/test_braking.py"],
    "experiments/car/assembly.py": [f"{CAR}/test_assembly.py", f"{EPISODE}/test_spec.py"],
    "experiments/link/outvote.py": ["tests/experiments/link/test_remote.py"],
    "core/vehicle.py": ["tests/test_clear_gap.py", "tests/experiments/scenarios/test_lead_vehicle.py"],
    "experiments/scenarios/lead_vehicle/following.py": ["tests/experiments/scenarios/test_lead_vehicle.py"],
    # The car ahead's broadcast, its attacks and the onboard fallback (issue 70).
    "sim/radio/message.py": ["tests/sim/radio/test_message.py", "tests/sim/radio/test_channel.py"],
    "sim/radio/keys.py": ["tests/sim/radio/test_message.py", "tests/sim/radio/test_keys.py"],
    # Key folders checked (issue 79), the link's and the fleet's.
    "core/keyfiles.py": ["tests/experiments/link/test_key_folders.py", "tests/sim/radio/test_keys.py"],
    "sim/radio/channel.py": ["tests/sim/radio/test_channel.py"],
    "experiments/car/broadcast.py": [f"{CAR}/test_broadcast.py", "tests/sim/attacks/test_radio_attacks.py",
                                     f"{CAR}/test_following_stage.py"],
    "sim/attacks/broadcast.py": ["tests/sim/attacks/test_radio_attacks.py"],
    # Results a user can check (issue 71): a card's episodes and its verification, a recording's mapping.
    "experiments/scorecard/verify.py": ["tests/experiments/scorecard/test_verify.py",
                                        "tests/experiments/scorecard/test_submission.py"],
    "experiments/scorecard/proof.py": ["tests/experiments/scorecard/test_verify.py"],
    "experiments/bags/mapping.py": ["tests/experiments/bags/test_mapping.py"],
}
#: The link's modules (the default run of `make mutate`); the others run with MODULES="...".
def mutated() -> list[str]:
    out = subprocess.run(["git", "diff", "--name-only", "--", *TESTS], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    return out.split()


def main(argv: list[str]) -> int:
    """Runs the mutated module's tests; ``--baseline MODULE``: that module's tests on the code as it is."""
    modules = argv[1:2] if argv[:1] == ["--baseline"] else mutated()
    if len(modules) != 1:
        print(f"expected one mutated module, git shows {modules}", file=sys.stderr)
        return 3
    # cosmic-ray turns bytecode off, which makes every run compile all of racf: it is on here, and the
    # mutated module's own bytecode is removed before and after (two mutants of one size written in
    # one second would otherwise share a stale .pyc).
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", MUJOCO_GL=env.get("MUJOCO_GL", "egl"))
    tests = TESTS[modules[0]]
    missing = [t for t in tests if not (ROOT / t).exists()]
    if missing:
        print(f"RUNNER ERROR: the tests of {modules[0]} are gone: {missing}")
        return 3
    forget_bytecode(modules[0])
    try:
        server = os.environ.get("RACF_MUTATION_FORKSERVER")
        if server and os.path.exists(server):  # a warm process forks the run (tests/mutation/forkserver.py)
            rc, last = _forked(server, modules[0], tests)
        else:
            run = subprocess.run([sys.executable, "-m", "pytest", *PYTEST_ARGS, *tests], cwd=ROOT, env=env, capture_output=True,
                                 text=True)
            rc, last = run.returncode, (run.stdout.strip().splitlines() or [""])[-1] + run.stderr[-300:]
    finally:
        forget_bytecode(modules[0])
    if rc not in (0, 1):  # not a verdict on the mutant: collection failed, no tests, ...
        print(f"RUNNER ERROR: pytest exited {rc}: {last}")
        return 1
    print(f"{modules[0]}: {last}")
    return rc


def _forked(path: str, module: str, tests: list[str]) -> tuple[int, str]:
    import json
    import socket

    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as conn:
        conn.connect(path)
        with conn.makefile("rw") as stream:
            stream.write(json.dumps({"module": module, "tests": tests}) + "\n")
            stream.flush()
            answer = json.loads(stream.readline())
    return answer["rc"], answer["last"]


def forget_bytecode(module: str) -> None:
    """Removes the compiled forms of ``module`` wherever Python may have cached them (beside the file
    and beside its link in the development install)."""
    stem = Path(module).stem
    for cache in [ROOT / Path(module).parent / "__pycache__", *(ROOT / "build").glob(
            f"__editable__*/racf/{Path(module).parent.relative_to(Path(module).parts[0])}/__pycache__")]:
        for pyc in cache.glob(f"{stem}.*.pyc"):
            pyc.unlink(missing_ok=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
