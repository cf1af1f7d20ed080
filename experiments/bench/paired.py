"""``racf bench paired``: this checkout's closed loop against another's, timed in alternation.

A speed change is only worth what it is measured against, and this machine's speed drifts by
10-30 % from minute to minute. So the two versions run side by side: one warm worker process
per checkout, both pinned to the same core with the sweep workers' single-thread settings,
each asked in turn (old, new, new, old, ...) to run the same episodes; each round gives the
ratio of their milliseconds a control step, and the median ratio is the change.

The worker's code is passed on its command line and uses only ``TrialSpec`` and
``run_trial``, which every racf checkout has, so the baseline can be any older commit
(``git worktree add /tmp/old <rev>``).
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from racf.errors import UserError

__all__ = ["PairedResult", "bench_paired", "checkout_root"]

#: Each worker: warm up, then run the episodes once per line read and print ms a control step.
_WORKER = """
import os, sys, time
os.sched_setaffinity(0, {int(sys.argv[1])})
from racf.experiments.episode import TrialSpec, run_trial
setting, n = sys.argv[2], int(sys.argv[3])
specs = [TrialSpec(setting, i % 4, (1.0, 1.5, 2.0)[(i // 4) % 3], 100 + i) for i in range(n)]
run_trial(TrialSpec(setting, 0, 1.5, 5000), clean_pass=False)
print("ready", flush=True)
for _ in sys.stdin:
    wall = steps = 0
    for spec in specs:
        start = time.perf_counter()
        _, log = run_trial(spec, clean_pass=False)
        wall += time.perf_counter() - start
        steps += len(log)
    print(wall / steps * 1000.0, flush=True)
"""


@dataclass(frozen=True)
class PairedResult:
    """Milliseconds a control step of each checkout, round by round, and their ratios."""

    setting: str
    episodes: int
    old_ms: tuple[float, ...]
    new_ms: tuple[float, ...]

    @property
    def ratios(self) -> list[float]:
        return [new / old for old, new in zip(self.old_ms, self.new_ms)]

    @property
    def ratio(self) -> float:
        """Median over rounds of new / old: below 1, this checkout is faster."""
        return statistics.median(self.ratios)

    def to_dict(self) -> dict:
        return {"setting": self.setting, "episodes": self.episodes, "old_ms": list(self.old_ms),
                "new_ms": list(self.new_ms), "ratios": self.ratios, "ratio": self.ratio,
                "old_rtf": 20.0 / statistics.median(self.old_ms), "new_rtf": 20.0 / statistics.median(self.new_ms)}


#: The packages a checkout maps under ``racf`` (pyproject's package-dir), and their folders.
_MAPPED = ("sim", "odca", "controllers", "experiments", "assets")


def checkout_root(path: str | Path) -> Path:
    """The folder of a racf checkout: one with ``core/__init__.py`` (racf's floor, the folders beside it
    mapped under ``racf``) or, before that layout, ``racf/__init__.py`` with links; UserError if
    ``path`` is neither."""
    root = Path(path).expanduser().resolve()
    if not ((root / "core" / "__init__.py").is_file() or (root / "racf" / "__init__.py").is_file()):
        raise UserError(f"--baseline must be a racf checkout (a folder with core/__init__.py, e.g. from `git worktree "
                        f"add /tmp/old HEAD~1`), got {path}")
    return root


def importable(root: Path, workdir: str) -> Path:
    """A folder that, put on ``PYTHONPATH``, imports ``racf`` from the checkout at ``root``: the checkout
    itself in the old layout, else a folder under ``workdir`` whose ``racf/`` links to the checkout's
    files as its package-dir maps them (what its development install builds)."""
    if (root / "racf" / "__init__.py").is_file():
        return root
    home = Path(tempfile.mkdtemp(dir=workdir, prefix="checkout-"))
    package = home / "racf"
    package.mkdir()
    for item in (root / "core").iterdir():
        (package / item.name).symlink_to(item)
    for name in _MAPPED:
        (package / name).symlink_to(root / name, target_is_directory=True)
    return home


def _start(root: Path, cpu: int, setting: str, episodes: int, workdir: str, errors) -> subprocess.Popen:
    from racf.experiments.sweeps.executors import SINGLE_THREAD_ENV

    env = {**os.environ, **SINGLE_THREAD_ENV, "PYTHONPATH": str(importable(root, workdir))}
    proc = subprocess.Popen([sys.executable, "-c", _WORKER, str(cpu), setting, str(episodes)], cwd=workdir, env=env,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=errors, text=True)
    if proc.stdout.readline().strip() != "ready":
        proc.kill()
        errors.seek(0)
        last = ([line.strip() for line in errors if line.strip()] or ["no output"])[-1]
        raise UserError(f"the checkout at {root} could not run a {setting} episode: {last}")
    return proc


def bench_paired(baseline: Path, rounds: int = 6, setting: str = "attack+odca", episodes: int = 6,
                 on_round=None) -> PairedResult:
    """``rounds`` alternating timings of ``episodes`` episodes in the ``baseline`` checkout and in this one."""
    import racf

    here = checkout_root(Path(racf.__file__).resolve().parents[1])
    cpu = min(os.sched_getaffinity(0))
    old_ms: list[float] = []
    new_ms: list[float] = []
    with tempfile.TemporaryDirectory() as workdir, \
            tempfile.TemporaryFile("w+") as old_err, tempfile.TemporaryFile("w+") as new_err:
        # The workers run in an empty folder: neither finds a racf in its working folder.
        workers: dict[str, subprocess.Popen] = {}
        try:
            workers["old"] = _start(baseline, cpu, setting, episodes, workdir, old_err)
            workers["new"] = _start(here, cpu, setting, episodes, workdir, new_err)
            for r in range(rounds):
                for name in (("old", "new") if r % 2 == 0 else ("new", "old")):
                    proc = workers[name]
                    proc.stdin.write("go\n")
                    proc.stdin.flush()
                    (old_ms if name == "old" else new_ms).append(float(proc.stdout.readline()))
                if on_round is not None:
                    on_round(r, old_ms[-1], new_ms[-1])
        finally:
            for proc in workers.values():
                proc.stdin.close()
                try:
                    proc.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    proc.kill()
    return PairedResult(setting, episodes, tuple(old_ms), tuple(new_ms))
