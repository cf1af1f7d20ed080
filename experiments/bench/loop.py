"""``racf bench-loop``: closed-loop throughput, as ratios a user can compare across machines.

- ``rtf_clean``, ``rtf_attack_odca``: simulated seconds per wall second of whole episodes on
  one core (torch on one thread), with the default sensors; clean, and under the strong
  patch attack with ODCA.
- ``episodes_per_min_1``, ``episodes_per_min_2``: sweep episodes per minute with 1 and 2
  spawned local workers on the same episodes; ``scaling_efficiency`` = rate with 2 /
  (2 x rate with 1).
- ``episodes_per_min_ray``: the Ray backend's rate with 2 CPUs.
Wall times include each backend's start-up (spawning workers, loading ODCA, starting Ray):
what a user waits for.
"""

from __future__ import annotations

import tempfile
import time

__all__ = ["bench_loop"]


def _episodes(setting: str, n: int, seed: int):
    from experiments.episode import TrialSpec

    return [TrialSpec(setting, i % 4, (1.0, 1.5, 2.0)[(i // 4) % 3], seed + i) for i in range(n)]


def _rtf(setting: str, n: int, seed: int) -> dict:
    from experiments.episode import run_trial

    run_trial(_episodes(setting, 1, seed + 1000)[0])  # warm up: renderer, ODCA checkpoint, caches
    sim_s = wall_s = 0.0
    for spec in _episodes(setting, n, seed):
        t0 = time.perf_counter()
        _, log = run_trial(spec, clean_pass=False)
        wall_s += time.perf_counter() - t0
        sim_s += len(log) / 50.0
    return {"rtf": sim_s / wall_s, "sim_s": sim_s, "wall_s": wall_s}


def _rate(backend: str, workers: int, specs) -> float:
    from experiments.sweeps.executors import ray_executor, run_episode

    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        if backend == "ray":
            for _ in ray_executor(specs, out, workers, False):
                pass
        else:
            from experiments.workers import spawn_pool

            # Spawned workers for 1 and 2 alike, so the ratio compares like with like.
            with spawn_pool(workers) as pool:
                list(pool.map(run_episode, specs, [out] * len(specs)))
        return len(specs) / (time.perf_counter() - t0) * 60.0


def bench_loop(n_rtf: int = 8, n_rate: int = 12, seed: int = 0, ray: bool = True, progress: bool = True) -> dict:
    """Measures everything above; ``n_rtf`` episodes per RTF setting, ``n_rate`` per rate."""
    from tqdm import tqdm

    from experiments.workers import single_thread

    single_thread()  # one core: torch, OpenMP and the software rasteriser on one thread
    steps = ["rtf clean", "rtf attack+odca", "1 worker", "2 workers"] + (["ray"] if ray else [])
    bar = tqdm(steps, desc="bench-loop", disable=not progress)
    out: dict = {}
    bar.set_postfix_str(steps[0])
    clean = _rtf("clean", n_rtf, seed)
    bar.update()
    bar.set_postfix_str(steps[1])
    attack = _rtf("attack+odca", n_rtf, seed)
    bar.update()
    specs = _episodes("attack+odca", n_rate, seed + 100)
    rates = {}
    for workers in (1, 2):
        bar.set_postfix_str(f"{workers} worker(s)")
        rates[workers] = _rate("local", workers, specs)
        bar.update()
    out.update(rtf_clean=clean["rtf"], rtf_attack_odca=attack["rtf"], episodes_per_min_1=rates[1],
               episodes_per_min_2=rates[2], scaling_efficiency=rates[2] / (2 * rates[1]))
    if ray:
        bar.set_postfix_str("ray")
        out["episodes_per_min_ray"] = _rate("ray", 2, specs)
        bar.update()
    bar.close()
    out.update(n_rtf=n_rtf, n_rate=n_rate, sim_s_clean=clean["sim_s"], sim_s_attack_odca=attack["sim_s"],
               torch_threads=1)
    return out
