"""Worker processes for episodes: spawned (never forked) and single-threaded.

A process that has made a GL context must not fork renderers, so workers are spawned. Each
worker runs one episode at a time on one core: torch and OpenMP on one thread, and Mesa's
software rasteriser (llvmpipe) on the calling thread (``LP_NUM_THREADS=0``: with one
rasteriser thread, handing it each frame made a frame about 20 % slower). Left at their
defaults, every worker would start as many threads as the machine has cores, and two workers
on two cores ran slower together than one alone (``racf bench-loop`` measured 0.25 scaling
efficiency).
"""

from __future__ import annotations

import multiprocessing as mp
import os
from concurrent.futures import ProcessPoolExecutor

__all__ = ["SINGLE_THREAD_ENV", "single_thread", "spawn_pool"]

#: Environment variables that keep a worker's libraries on one thread (read when they start).
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "LP_NUM_THREADS": "0"}


def single_thread() -> None:
    """Pins this process's numeric and rendering libraries to one thread (call before rendering)."""
    for key, value in SINGLE_THREAD_ENV.items():
        os.environ[key] = value
    try:
        import torch

        torch.set_num_threads(1)
    except ImportError:  # torch is a dependency; this only keeps the helper importable without it
        pass


def spawn_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned, single-threaded processes."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"), initializer=single_thread)
