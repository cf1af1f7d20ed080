"""Falsification: Optuna searches the space for the episodes with the lowest stop-rule robustness.

Each search is one Optuna study (a sampler and a search seed) kept in a journal file under
``out/studies/``, so a search killed at any point resumes from its stored trials. Searches run in
rounds: every unfinished study asks for ``batch`` trials, all their episodes run on one pool,
and the values are told in trial order. The order never depends on which episode finished first,
so the same command gives the same searches on any machine, with any number of workers.

A trial's episode seed is ``search seed * 100000 + trial number``: what the evaluation is, so
every sampler meets the same noise at the same step of its budget. The objective is the
episode's robustness (``episode.robustness``; negative: the stop rule was broken), or with
``objective="rule-undetected"`` that minus the attack's undetected error, or with ``objective="gap"``
the smallest clear gap to the car ahead (negative: contact; the supervisor's guarantee) (``OBJECTIVES``).

A study's file is named by what made its values: the space, the defence and attacks, the
sampler and seed, the batch, racf's episode code and the plug-ins' sources. Other code makes a
new study; a stale one is never resumed.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

from racf.experiments.episode.spec import EPISODE_CODE, plugin_sources
from racf.experiments.falsify.pool import EpisodePool
from racf.experiments.falsify.space import SearchSpace
from racf.provenance import code_version

__all__ = ["SAMPLERS", "OBJECTIVES", "SearchConfig", "make_sampler", "run_searches", "episode_seed", "study_key",
           "objective_value"]

from racf.experiments.falsify.choices import OBJECTIVES, SAMPLERS  # noqa: E402,F401  (their home)
#: With ``objective="gap"``, a contact scores this far below a zero gap, m (the boxes touch at a gap of about 0).
CONTACT_M = 0.01
#: The objectives whose own value is the violation's measure (below zero: violated); the others are
#: judged by the stop rule's robustness.
VIOLATED_BY_VALUE = ("rule", "gap")
#: Random trials before the guided samplers model the space.
STARTUP_TRIALS = 10


def episode_seed(search_seed: int, number: int) -> int:
    """The episode seed of trial ``number`` of the search with ``search_seed``."""
    return int(search_seed) * 100_000 + int(number)


def make_sampler(name: str, seed: int):
    """Optuna's sampler ``name`` (``SAMPLERS``), seeded. CMA-ES models the numeric dimensions and
    draws the categorical ones (sign, effect) at random, as Optuna's CmaEsSampler does."""
    import optuna

    if name == "tpe":
        return optuna.samplers.TPESampler(seed=seed, n_startup_trials=STARTUP_TRIALS, multivariate=True,
                                          constant_liar=True)
    if name == "cmaes":
        return optuna.samplers.CmaEsSampler(seed=seed, n_startup_trials=STARTUP_TRIALS, warn_independent_sampling=False,
                                            independent_sampler=optuna.samplers.RandomSampler(seed=seed))
    if name == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    raise ValueError(f"sampler must be one of {SAMPLERS}, got {name!r}")


@dataclass(frozen=True)
class SearchConfig:
    """A set of searches: every sampler x every seed, each with ``budget`` episodes."""

    space: SearchSpace
    samplers: tuple[str, ...] = ("tpe",)
    seeds: tuple[int, ...] = (0,)
    budget: int = 100
    batch: int = 4
    stop_at_violation: bool = False
    objective: str = "rule"

    def __post_init__(self) -> None:
        if self.objective not in OBJECTIVES:
            raise ValueError(f"objective must be one of {OBJECTIVES}, got {self.objective!r}")
        bad = [s for s in self.samplers if s not in SAMPLERS]
        if not self.samplers or bad:
            raise ValueError(f"samplers must be a non-empty subset of {SAMPLERS}, got {list(self.samplers)}")
        if not self.seeds or not all(isinstance(s, int) and 0 <= s < 10_000 for s in self.seeds):
            raise ValueError(f"seeds must be integers in [0, 10000), got {list(self.seeds)}")
        if not (isinstance(self.budget, int) and 1 <= self.budget <= 100_000):
            raise ValueError(f"budget must be an integer number of episodes in [1, 100000], got {self.budget!r}")
        if not (isinstance(self.batch, int) and 1 <= self.batch <= 64):
            raise ValueError(f"batch must be an integer in [1, 64], got {self.batch!r}")


def objective_value(row, objective: str) -> float:
    """What the search minimises for one episode's result row (NaN: not a point of the search)."""
    if objective == "gap":  # the clear gap to the car ahead: below zero once they touch
        gap = _finite(row.get("min_gap_m"))
        return min(gap, 0.0) - CONTACT_M if row.get("no_lead_collision") is False else gap
    value = _finite(row.get("robustness_m"))
    if objective == "rule-undetected":
        value -= _finite(row.get("undetected_error_m"), 0.0)
    return value


def _finite(value, default: float = math.nan) -> float:
    return float(value) if value is not None and value == value else default


def study_key(space: SearchSpace, sampler: str, seed: int, batch: int, objective: str = "rule") -> str:
    """What a study's values depend on, hashed: a new key is a new study."""
    probe = space.trial_spec({d.name: (d.choices[0] if d.choices is not None else d.low) for d in space.dimensions}, 0)
    payload = {"space": space.to_json(), "sampler": sampler, "seed": seed, "batch": batch,
               "code": code_version(*EPISODE_CODE), "plugins": plugin_sources(probe),
               "startup": STARTUP_TRIALS, **({"objective": objective} if objective != "rule" else {})}
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()[:12]


class _Search:
    """One study and its bookkeeping."""

    def __init__(self, cfg: SearchConfig, sampler: str, seed: int, folder: Path, store=None) -> None:
        import optuna
        from optuna.storages.journal import JournalFileBackend, JournalStorage

        self.cfg, self.sampler, self.seed, self.store = cfg, sampler, seed, store
        self._robustness: dict[int, float] = {}
        key = study_key(cfg.space, sampler, seed, cfg.batch, cfg.objective)
        self.name = f"{sampler}-seed{seed}-{key}"
        folder.mkdir(parents=True, exist_ok=True)
        storage = JournalStorage(JournalFileBackend(str(folder / f"{self.name}.jsonl")))
        self.study = optuna.create_study(study_name=self.name, storage=storage, direction="minimize",
                                         sampler=make_sampler(sampler, seed), load_if_exists=True)

    def trials(self) -> list[tuple[int, dict, float]]:
        """(number, parameters, robustness) of the told trials, in order, up to the budget."""
        from optuna.trial import TrialState

        done = sorted(self.study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)),
                      key=lambda t: t.number)[: self.cfg.budget]
        if self.cfg.objective in VIOLATED_BY_VALUE:
            return [(t.number, dict(t.params), float(t.value)) for t in done]
        missing = [t for t in done if t.number not in self._robustness]
        if missing:  # a resumed search: the rule's robustness is in the episodes' rows
            ids = [self.cfg.space.trial_spec(t.params, episode_seed(self.seed, t.number)).trial_id for t in missing]
            for t, (_, row) in zip(missing, self.store.rows(ids).iterrows()):
                self._robustness[t.number] = _finite(row.get("robustness_m"))
        return [(t.number, dict(t.params), self._robustness[t.number]) for t in done]

    def values(self) -> list[float]:
        return [value for *_, value in self.trials()]

    @property
    def done(self) -> bool:
        values = self.values()
        return len(values) >= self.cfg.budget or (self.cfg.stop_at_violation and any(v < 0 for v in values))

    def pending(self) -> list:
        """This round's trials: those asked and never told (a killed run's) first, then new ones."""
        from optuna.trial import TrialState

        space = self.cfg.space
        names = {d.name for d in space.dimensions}
        trials = []
        for frozen in sorted(self.study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)),
                             key=lambda t: t.number):
            if set(frozen.params) == names:
                trials.append((frozen.number, dict(frozen.params)))
            else:  # killed while its parameters were drawn: it never ran
                self.study.tell(frozen.number, state=TrialState.FAIL)
        room = min(self.cfg.batch, self.cfg.budget - len(self.values())) - len(trials)
        # A sampler's random state is not stored with the study: seed it afresh each round from
        # what the round is, so a resumed search asks what an uninterrupted one would have.
        self.study.sampler = make_sampler(self.sampler, self.seed * 100_003 + len(self.study.trials))
        for _ in range(max(room, 0)):
            trial = self.study.ask()
            trials.append((trial.number, space.suggest(trial)))
        return trials

    def tell(self, number: int, row) -> None:
        from optuna.trial import TrialState

        value = objective_value(row, self.cfg.objective)
        self._robustness[number] = value if self.cfg.objective in VIOLATED_BY_VALUE else _finite(row.get("robustness_m"))
        if math.isfinite(value):
            self.study.tell(number, value)
        else:  # no robustness (no stop line): not a point of the search
            self.study.tell(number, state=TrialState.FAIL)


def run_searches(cfg: SearchConfig, out: str | Path, pool: EpisodePool, progress: bool = True) -> dict:
    """Runs (or resumes) every search of ``cfg``; returns each search by ``(sampler, seed)`` (its ``trials()``:
    number, parameters and the rule's robustness of every told trial)."""
    import optuna
    from tqdm import tqdm

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    folder = Path(out) / "studies"
    searches = [_Search(cfg, sampler, seed, folder, getattr(pool, "store", None))
                for sampler in cfg.samplers for seed in cfg.seeds]
    total = len(searches) * cfg.budget
    bar = tqdm(total=total, initial=sum(min(len(s.values()), cfg.budget) for s in searches), desc="falsify",
               unit="episode", disable=not progress)
    while True:
        live = [s for s in searches if not s.done]
        if not live:
            break
        rounds = [(s, number, params, cfg.space.trial_spec(params, episode_seed(s.seed, number)))
                  for s in live for number, params in s.pending()]
        rows = pool.run([spec for *_, spec in rounds])
        for (search, number, _, _), (_, row) in zip(rounds, rows.iterrows()):
            search.tell(number, row)
        bar.update(len(rounds))
        bar.set_postfix_str(f"lowest {min(min(s.values(), default=math.inf) for s in searches):+.3f} m")
    bar.close()
    return {(s.sampler, s.seed): s for s in searches}
