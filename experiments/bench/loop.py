"""``racf bench loop``: closed-loop throughput, as ratios a user can compare across machines.

- ``rtf_clean``, ``rtf_attack_odca``: simulated seconds per wall second of whole episodes
  (reset included) on one core (torch on one thread, the rasteriser on the calling thread),
  with the default sensors; clean, and under the strong patch attack with ODCA. Episodes run
  as a sweep runs them: without the d_clean diagnostic pass (``run_trial(clean_pass=False)``).
- ``episodes_per_min_1``, ``episodes_per_min_2``: sweep episodes per minute with 1 and 2
  spawned local workers, once the workers are up, over the same episodes run twice in
  alternation (1, 2, 1, 2 workers); ``scaling_efficiency`` = rate with 2 / (2 x rate with 1).
- ``episodes_per_min_ray``: the same on the Ray backend with 2 CPUs.
- ``share_*``: where an attack + ODCA episode's time goes (render, LiDAR, physics, perception,
  the estimator, the rest), from one profiled episode (:mod:`racf.experiments.bench.profile`).
- ``ready_s_*``: what each backend takes to be ready (spawning, imports, the env, ODCA; one
  warm-up episode per worker), reported apart because a sweep pays it once, not per episode.
"""

from __future__ import annotations

import os
import tempfile
import time

__all__ = ["bench_loop"]

#: The rate runs' episodes: attack + ODCA on every sign at every speed.
_RATE_SETTING = "attack+odca"


def _episodes(setting: str, n: int, seed: int, profile: str):
    from racf.experiments.episode import TrialSpec

    return [TrialSpec(setting, i % 4, (1.0, 1.5, 2.0)[(i // 4) % 3], seed + i, sensor_profile=profile)
            for i in range(n)]


def _rtf(setting: str, n: int, seed: int, profile: str) -> dict:
    from racf.experiments.episode import run_trial

    run_trial(_episodes(setting, 1, seed + 1000, profile)[0])  # warm up: the env, ODCA checkpoint, caches
    sim_s = wall_s = 0.0
    for spec in _episodes(setting, n, seed, profile):
        t0 = time.perf_counter()
        _, log = run_trial(spec, clean_pass=False)
        wall_s += time.perf_counter() - t0
        sim_s += len(log) / 50.0
    return {"rtf": sim_s / wall_s, "sim_s": sim_s, "wall_s": wall_s}


def _warm(barrier=None, profile: str = "qcar2") -> int:
    """Readies a worker with one episode (imports, the env, ODCA), then waits for the others,
    so that every worker takes one; returns the worker's pid."""
    from racf.experiments.episode import run_trial

    run_trial(_episodes(_RATE_SETTING, 1, 10_000, profile)[0], clean_pass=False)
    if barrier is not None:
        barrier.wait(timeout=600)
    return os.getpid()


def _slowest_first(specs):
    # Slow approaches are the long episodes: started first, they leave no worker idle at the end.
    return sorted(specs, key=lambda spec: spec.speed)


def _local_rates(specs, rounds: int = 2) -> tuple[dict[int, float], dict[int, float]]:
    """Episodes per minute once ready, and seconds to ready, with 1 and 2 spawned workers.

    Both pools are up at once (an idle worker sleeps) and run ``specs`` in turn, ``rounds``
    times, so a machine whose speed drifts slows both alike.
    """
    import multiprocessing as mp
    from contextlib import ExitStack

    from racf.experiments.sweeps.executors import run_episode
    from racf.experiments.sweeps.executors import spawn_pool

    counts = (1, 2)
    elapsed, ready = dict.fromkeys(counts, 0.0), {}
    with tempfile.TemporaryDirectory() as out, ExitStack() as stack:
        manager = stack.enter_context(mp.get_context("spawn").Manager())
        pools = {}
        for workers in counts:
            t0 = time.perf_counter()
            pools[workers] = stack.enter_context(spawn_pool(workers))
            profiles = [specs[0].sensor_profile] * workers
            pids = list(pools[workers].map(_warm, [manager.Barrier(workers)] * workers, profiles))
            if len(set(pids)) != workers:
                raise RuntimeError(f"warm-up reached {len(set(pids))} of {workers} workers")
            ready[workers] = time.perf_counter() - t0
        for _ in range(rounds):
            for workers in counts:
                t0 = time.perf_counter()
                list(pools[workers].map(run_episode, specs, [out] * len(specs)))
                elapsed[workers] += time.perf_counter() - t0
    return {w: rounds * len(specs) / elapsed[w] * 60.0 for w in counts}, ready


def _ray_rate(workers: int, specs) -> tuple[float, float]:
    import ray

    from racf.experiments.sweeps.executors import ray_executor, ray_session

    with tempfile.TemporaryDirectory() as out, ray_session(workers):
        t0 = time.perf_counter()
        # Tasks that outlast a worker's start-up each get their own worker; Ray keeps them.
        ray.get([ray.remote(num_cpus=1)(_warm).remote(None, specs[0].sensor_profile) for _ in range(workers)])
        t1 = time.perf_counter()
        for _ in ray_executor(specs, out, workers):
            pass
        t2 = time.perf_counter()
    return len(specs) / (t2 - t1) * 60.0, t1 - t0


def bench_loop(n_rtf: int = 8, n_rate: int = 48, seed: int = 0, ray: bool = True, progress: bool = True,
               sensor_profile: str = "qcar2") -> dict:
    """Measures everything above on ``sensor_profile``; ``n_rtf`` episodes per RTF setting, ``n_rate`` per rate."""
    from tqdm import tqdm

    from racf.experiments.bench.profile import step_profile
    from racf.experiments.sweeps.executors import single_thread

    single_thread()  # one core: torch, OpenMP and the software rasteriser on one thread
    steps = ["rtf clean", "rtf attack+odca", "1 worker", "2 workers"] + (["ray"] if ray else []) + ["profile"]
    bar = tqdm(steps, desc="bench-loop", disable=not progress)
    out: dict = {}
    bar.set_postfix_str(steps[0])
    clean = _rtf("clean", n_rtf, seed, sensor_profile)
    bar.update()
    bar.set_postfix_str(steps[1])
    attack = _rtf(_RATE_SETTING, n_rtf, seed, sensor_profile)
    bar.update()
    specs = _slowest_first(_episodes(_RATE_SETTING, n_rate, seed + 100, sensor_profile))
    bar.set_postfix_str("1 and 2 workers")
    rates, ready = _local_rates(specs)
    bar.update(2)
    out.update(rtf_clean=clean["rtf"], rtf_attack_odca=attack["rtf"], episodes_per_min_1=rates[1],
               episodes_per_min_2=rates[2], scaling_efficiency=rates[2] / (2 * rates[1]))
    if ray:
        bar.set_postfix_str("ray")
        out["episodes_per_min_ray"], ready["ray"] = _ray_rate(2, specs)
        bar.update()
    bar.set_postfix_str("profile")
    shares = step_profile(_RATE_SETTING, profile=sensor_profile)["shares"]
    out.update({f"share_{part}": share for part, share in shares.items()})
    bar.update()
    bar.close()
    out.update(sensor_profile=sensor_profile, n_rtf=n_rtf, n_rate=n_rate, sim_s_clean=clean["sim_s"],
               sim_s_attack_odca=attack["sim_s"], ready_s_1=ready[1], ready_s_2=ready[2], torch_threads=1)
    if ray:
        out["ready_s_ray"] = ready["ray"]
    return out
