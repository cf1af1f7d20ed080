"""An episode that did not finish, in words: which part raised (a user's plug-in, one of racf's
own parts, or racf itself), the exception, the episode, and the full traceback for the log."""

from __future__ import annotations

import importlib.util
import inspect
import traceback
from pathlib import Path

from racf.errors import Failure
from racf.experiments.episode import TrialSpec
from racf.experiments.scenarios.base import params_label

__all__ = ["describe", "worker_died", "plugin_fault", "episode_words", "params_words", "append_log", "LOG_NAME"]

#: The file under a batch's results folder that holds its failures' tracebacks.
LOG_NAME = "failures.log"


def episode_words(spec: TrialSpec) -> str:
    """``attack+odca sign1 v1.50 seed 3 (id ...)``: enough to find and rerun the episode (a scenario's
    parameters come after its name: ``stale_map[case=removed, shift_m=1.0]1``)."""
    return (f"{spec.setting} {spec.target}{params_words(spec.scenario_params)}{spec.sign} v{spec.speed:.2f} "
            f"seed {spec.seed} (id {spec.trial_id})")


def params_words(values: dict) -> str:
    """``[case=removed, shift_m=1.0]``: a scenario's parameter values ('' for a scenario without any)."""
    return f"[{params_label(values)}]" if values else ""


def describe(spec: TrialSpec, err: BaseException) -> Failure:
    """The failure of ``spec``'s episode that ``err`` ended: the part named is the innermost frame
    of the traceback that lies in one of the episode's parts (its estimator, attacks, detector,
    scenario with its world managers and criteria, metrics)."""
    where = _innermost(err, _parts(spec)) or "racf"
    return Failure(spec.trial_id, where, f"{type(err).__name__}: {err}", "".join(traceback.format_exception(err)),
                   episode_words(spec))


def _innermost(err: BaseException, parts: list[tuple[str, Path]]) -> str | None:
    """The label of the part whose code holds the innermost frame of ``err``'s traceback, if any."""
    files = [Path(frame.f_code.co_filename).resolve() for frame, _ in traceback.walk_tb(err.__traceback__)]
    for file in reversed(files):
        for label, home in parts:
            if file == home or home in file.parents:
                return label
    return None


def worker_died(spec: TrialSpec) -> Failure:
    """The failure of an episode whose worker process died under it twice."""
    return Failure(spec.trial_id, "a worker process", "its process died twice while running it (killed, or out of "
                   "memory)", "no traceback: the process was killed", episode_words(spec))


def append_log(folder: Path, failure: Failure, first: bool) -> Path:
    """Adds ``failure`` to ``folder``'s log (a new log for a batch's first failure); returns its path."""
    path = Path(folder) / LOG_NAME
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w" if first else "a") as log:
        log.write(f"=== episode {failure.spec}\n{failure.where} raised {failure.error}\n{failure.traceback}\n")
    return path


def _parts(spec: TrialSpec) -> list[tuple[str, Path]]:
    """(label, the file or package folder of its code) of each registered part the episode runs."""
    from racf.plugins import REGISTRIES

    named = [("estimator", spec.estimator), *[("attack", a) for a in spec.attacks], ("detector", spec.detector),
             ("scenario", spec.target), *[("metric", m) for m in spec.metric_names]]
    out = []
    for kind, name in named:
        plugin = REGISTRIES[kind].plugin(name)
        home = _home(plugin)
        if home is not None:
            label = f"{kind} {name!r}" if plugin.builtin else f"{kind} plug-in {name!r} ({plugin.origin})"
            out.append((label, home))
    return out


def _home(plugin) -> Path | None:
    """Where a part's code lives: a plug-in package's folder, else the file defining the class."""
    if plugin.source and not plugin.source.startswith("code:") and not Path(plugin.source).is_absolute():
        spec = importlib.util.find_spec(plugin.source)  # an installed plug-in: its whole package
        if spec is not None and spec.submodule_search_locations:
            return Path(next(iter(spec.submodule_search_locations))).resolve()
    try:
        file = inspect.getsourcefile(plugin.obj)
    except TypeError:  # defined where no file holds it
        return None
    return Path(file).resolve() if file else None


def plugin_fault(err: BaseException) -> Failure | None:
    """``err`` as a failure of a user's plug-in, if a frame of its traceback lies in one (the
    innermost such frame names it); None for an error of racf's own code."""
    from racf.plugins import REGISTRIES

    homes = []
    for kind, registry in REGISTRIES.items():
        for name in registry:
            plugin = registry.plugin(name)
            home = None if plugin.builtin else _home(plugin)
            if home is not None:
                homes.append((f"{kind} plug-in {name!r} ({plugin.origin})", home))
    label = _innermost(err, homes)
    if label is None:
        return None
    return Failure("", label, f"{type(err).__name__}: {err}", "".join(traceback.format_exception(err)),
                   "outside an episode")
