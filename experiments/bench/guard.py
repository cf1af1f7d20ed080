"""The speed guard: the closed loop's cost as a ratio to MuJoCo's bare physics step, measured in
one run, so that a slower machine (or a busy minute) moves both and the ratio stays.

One round times one fixed episode (attack + ODCA, the ``qcar2`` profile at 320 x 240: a control
step with everything in it) and, right after, the same number of bare physics steps of the same
model (``mj_step`` x the env's substeps, no sensors). Rounds alternate the two, and the guard's
number is the median over rounds of (loop seconds a step) / (physics seconds a step). It is
stored per commit in ``docs/results/data/speed-guard.json``; ``make check-speed`` fails when the
ratio is more than ``TOLERANCE`` above the stored one. Not for CI: shared machines are too noisy.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

__all__ = ["GuardResult", "measure_guard", "TOLERANCE", "GUARD_SPEC"]

#: How much worse than the stored ratio a change may make the loop before the guard fails.
TOLERANCE = 0.15
#: The episode the guard times: (setting, sign, speed, seed).
GUARD_SPEC = ("attack+odca", 0, 1.5, 0)


@dataclass(frozen=True)
class GuardResult:
    """Per round: the loop's and the bare physics' seconds a control step; their ratio's median."""

    loop_step_ms: list[float]
    physics_step_ms: list[float]
    ratios: list[float]
    steps: int
    slowdown: float

    @property
    def ratio(self) -> float:
        return statistics.median(self.ratios)

    def to_dict(self) -> dict:
        return {"ratio": self.ratio, "ratios": self.ratios, "loop_step_ms": self.loop_step_ms,
                "physics_step_ms": self.physics_step_ms, "steps": self.steps, "slowdown": self.slowdown,
                "rtf_loop": 20.0 / statistics.median(self.loop_step_ms)}


def _busy(seconds: float) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def measure_guard(rounds: int = 5, slowdown: float = 1.0) -> GuardResult:
    """``rounds`` alternating timings of the loop and of bare physics (after a warm-up episode).
    ``slowdown`` > 1 makes the loop that much slower on purpose (busy work after each step, sized
    from the warm-up's step time): the check that the guard catches a regression."""
    import gymnasium as gym
    import mujoco

    from racf import sim
    from racf.experiments.episode import TrialSpec, run_trial
    from racf.experiments.episode.plan import env_settings

    setting, sign, speed, seed = GUARD_SPEC
    spec = TrialSpec(setting, sign, speed, seed)
    run_trial(spec, clean_pass=False)  # warm: imports, the env, the checkpoint
    start = time.perf_counter()
    _, log = run_trial(spec, clean_pass=False)
    steps = len(log)
    extra = (slowdown - 1.0) * (time.perf_counter() - start) / steps  # the made-up slowdown's share of a step

    def hook(env, obs, info, row) -> None:
        _busy(extra)

    env = gym.make(sim.ENV_ID, **env_settings(spec))
    env.reset(seed=seed, options={"sign": sign, "cruise_speed": speed})
    model, data = env.unwrapped.model, env.unwrapped.data
    substeps = env.unwrapped.config.substeps
    snapshot = (data.qpos.copy(), data.qvel.copy(), data.act.copy(), data.ctrl.copy())
    loop, physics = [], []
    for _ in range(rounds):
        start = time.perf_counter()
        _, log = run_trial(spec, clean_pass=False, on_step=hook if slowdown > 1.0 else None)
        loop.append((time.perf_counter() - start) / len(log) * 1000.0)
        data.qpos[:], data.qvel[:], data.act[:], data.ctrl[:] = snapshot
        mujoco.mj_forward(model, data)
        start = time.perf_counter()
        for _ in range(steps * substeps):
            mujoco.mj_step(model, data)
        physics.append((time.perf_counter() - start) / steps * 1000.0)
    env.close()
    ratios = [a / b for a, b in zip(loop, physics)]
    return GuardResult([float(x) for x in loop], [float(x) for x in physics], [float(r) for r in ratios], steps,
                       float(slowdown))
