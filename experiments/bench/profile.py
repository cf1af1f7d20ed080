"""Where an episode's time goes: the shares of the camera's rendering, the LiDAR, the physics,
perception, the distance estimator and the rest, from one profiled episode per setting.

Measured with cProfile over whole episodes (reset included) on one thread. Each part is the
cumulative time of the functions that do it, so the parts are disjoint and ``rest`` is the
episode's time less them (the env's bookkeeping, the braker, logging, the profiler's own
overhead, which inflates small Python calls). Use the shares to see what to speed up, not as
timings: the benchmark's real-time factors are the timings.
"""

from __future__ import annotations

import cProfile
import pstats

__all__ = ["PARTS", "step_profile"]

#: Each part: (module path fragment, function names) whose cumulative time it counts.
PARTS = {
    "render": (("sim/sensors/camera.py", ("render",)),),
    "lidar": (("sim/sensors/a2m12.py", ("sweep", "read", "begin")), ("sim/sensors/lidar.py", ("read",))),
    "physics": (("~", ("<built-in method mujoco._functions.mj_step>",)),),
    "perception": (("controllers/perception.py", ("process",)),),
    "estimator": (("controllers/estimators.py", ("estimate",)), ("experiments/car/estimators.py", ("estimate",)),
                  ("controllers/baselines/", ("estimate",))),
}


def _part_seconds(stats: pstats.Stats) -> dict[str, float]:
    seconds = dict.fromkeys(PARTS, 0.0)
    for (path, _, func), (_, _, _, cumulative, _) in stats.stats.items():
        for part, rules in PARTS.items():
            if any(fragment in path.replace("\\", "/") and func in names for fragment, names in rules):
                seconds[part] += cumulative
    return seconds


def step_profile(setting: str = "attack+odca", sign: int = 0, speed: float = 1.5, seed: int = 0,
                 profile: str = "qcar2") -> dict:
    """The shares of one episode's time, after a warm-up episode (imports, the env, the checkpoint)."""
    from racf.experiments.episode import TrialSpec, run_trial

    spec = TrialSpec(setting, sign, speed, seed, sensor_profile=profile)
    run_trial(TrialSpec(setting, sign, speed, seed + 1000, sensor_profile=profile), clean_pass=False)
    profiler = cProfile.Profile()
    profiler.enable()
    run_trial(spec, clean_pass=False)
    profiler.disable()
    stats = pstats.Stats(profiler)
    total = stats.total_tt
    parts = _part_seconds(stats)
    parts["rest"] = max(0.0, total - sum(parts.values()))
    return {"setting": setting, "total_s": total, "shares": {k: v / total for k, v in parts.items()}}
