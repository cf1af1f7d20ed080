"""``racf board verify``: a card proves itself by being measured again.

Leaderboards that matter re-evaluate what is submitted (RobustBench re-runs the model, CARLA's
organisers run the agent). A card here carries every episode's record and step-log digest
(:mod:`racf.experiments.scorecard.proof`), so checking it takes three steps, row by row:

1. **the code**: the card's version must be this checkout's (a plug-in's source included); a
   card of other code is refused before anything runs, naming the commit to check out;
2. **the episodes**: the row's episode ids must be the ones the battery makes for this defence
   today, and its summary (every rate, interval and median on the card) must be what its
   carried records give, so a number changed by hand is refused, naming the row;
3. **the bits**: a sample of each row's episodes is run again, and each must give the carried
   record and step log to the bit.

The sample is drawn afresh each time (its seed is printed, to repeat it): a sample the card's
maker could predict is one they could avoid. An episode changed on a card escapes one
verification with probability ``1 - k/N`` per changed episode (k re-run of a row's N); the
summary check catches any change to a number the episodes do not give. Rows served over a link
(``racf serve``) are checked by steps 1 and 2 only: the round trips' timing is the machine's, so
such episodes do not repeat to the bit.
"""

from __future__ import annotations

import json
import math
import secrets
import shutil
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

from racf.errors import UserError

__all__ = ["RowVerdict", "verify_card", "summary_differences"]


@dataclass(frozen=True)
class RowVerdict:
    """What verification found for one row of a card."""

    key: str
    n: int
    rerun: int
    seconds: float
    problems: tuple[str, ...] = ()
    note: str = ""

    @property
    def ok(self) -> bool:
        return not self.problems


def summary_differences(card_row: dict, recomputed: dict, where: str = "") -> list[str]:
    """Where a card's row says other than its episodes give: ``'scr is 0.99, its episodes give 0.25'``
    for each value that differs (floats within 1e-9, as one machine's sums may order differently)."""
    out = []
    for key, value in recomputed.items():
        name = f"{where}{key}"
        if key not in card_row:
            out.append(f"{name} is missing")
        elif isinstance(value, dict) and isinstance(card_row[key], dict):
            out += summary_differences(card_row[key], value, f"{name}.")
        elif not _same(card_row[key], value):
            out.append(f"{name} is {_short(card_row[key])}, its episodes give {_short(value)}")
    return out


def _same(a, b) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, (int, float)) or not isinstance(b, (int, float)):
        return _json(a) == _json(b)
    if not (math.isfinite(a) and math.isfinite(b)):
        return False  # a card is strict JSON: a non-finite number on either side is not a summary's
    return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)


def _json(value) -> str:
    return json.dumps(value, sort_keys=True, allow_nan=True, default=str)


def _short(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else _json(value)[:60]


def _battery(card: dict):
    from racf.experiments.scorecard.battery import BATTERIES

    name = str(card.get("battery", ""))
    if "@" in name:
        raise UserError(f"the card's battery {name!r} runs in another scenario: verify takes racf's batteries as "
                        "released")
    battery = BATTERIES.get(name.removesuffix("-quick"))
    if battery is None:
        raise UserError(f"the card's battery {name!r} is none of racf's ({', '.join(BATTERIES)})")
    return battery


def _check_code(card: dict) -> None:
    from racf.experiments.scorecard.card import card_version
    from racf.plugins import ESTIMATORS

    defence = str(card.get("defence"))
    if defence not in ESTIMATORS:
        raise UserError(f"the card's defence {defence!r} is not registered here: give its plug-in (--plugin) as "
                        "the card's command did")
    mine = card_version(defence)
    if card.get("version") != mine:
        raise UserError(f"the card was measured by code {card.get('version')!r}, this checkout runs {mine!r}: "
                        f"check out its commit {card.get('commit')} (and the plug-in as it was) and verify there")
    if "episodes" not in card:
        raise UserError("the card carries no episodes (made before racf put them on cards): card it again")


def _row_specs(row, card: dict) -> list:
    specs = row.specs(card["defence"], bool(card.get("quick")))
    options = card.get("options") if card.get("options") is not None else {}
    return [replace(s, estimator_options=options) for s in specs] if options else specs


def _check_summary(row, section: dict, episodes: dict, ids: list[str]) -> list[str]:
    from racf.experiments.scorecard.card import row_summary
    from racf.experiments.scorecard.proof import episode_frame

    frame = episode_frame(episodes)
    if "trial_id" not in frame or list(frame["trial_id"]) != ids:
        return ["its episodes are not the ones the battery makes for this defence (their ids differ)"]
    if len(episodes.get("log_sha256", [])) != len(ids):
        return [f"it carries {len(episodes.get('log_sha256', []))} log digests for {len(ids)} episodes"]
    return summary_differences(section, row_summary(frame, row.attacked))


def _rerun(specs: list, episodes: dict, picks: list[int], pool, store) -> list[str]:
    """Runs the picked episodes again; what differs from the card's records and log digests."""
    import pandas as pd

    from racf.experiments.scorecard.proof import log_digest, record_of
    from racf.experiments.sweeps.run import run_episodes

    chosen = [specs[i] for i in picks]
    run_episodes(chosen, store, pool=pool, log_steps=True, progress=False)
    problems = []
    for i, spec in zip(picks, chosen):
        got = record_of(store.rows([spec.trial_id]).iloc[0].to_dict())
        carried = dict(zip(episodes["columns"], episodes["values"][i]))
        if _json(got) != _json(carried):
            fields = sorted(k for k in got.keys() | carried.keys() if _json(got.get(k)) != _json(carried.get(k)))
            problems.append(f"episode {spec.trial_id} does not reproduce: {', '.join(fields[:4])} differ")
        elif log_digest(pd.read_parquet(store.log_path(spec.trial_id))) != episodes["log_sha256"][i]:
            problems.append(f"episode {spec.trial_id} does not reproduce: its step log differs")
    return problems


def verify_card(card: dict, *, sample: int = 5, seed: int | None = None, workers: int = 2, backend: str = "local",
                address: str | None = None, progress=None) -> tuple[list[RowVerdict], int]:
    """Verifies ``card`` row by row; returns each row's verdict and the sample's seed.

    Args:
        sample: episodes re-run per row (at most the row's N; 0 checks the records only).
        seed: the sample's seed (None: a fresh one, returned to repeat the draw).
        progress: called with each row's verdict as it is made.

    Raises:
        UserError: the card is of another battery or code, or carries no episodes (nothing runs).
    """
    import random

    from racf.experiments.sweeps.executors import Workers
    from racf.experiments.sweeps.store import ResultStore

    if sample < 0:
        raise UserError(f"--sample must be >= 0, got {sample}")
    battery = _battery(card)
    _check_code(card)
    seed = secrets.randbits(32) if seed is None else int(seed)
    rng = random.Random(seed)
    folder = Path(tempfile.mkdtemp(prefix="racf-verify-"))
    verdicts = []
    try:
        store = ResultStore(folder / "episodes")
        with Workers(backend, workers, address) as pool:
            for row in battery.rows():
                verdicts.append(_verify_row(row, card, sample, rng, pool, store))
                if progress is not None:
                    progress(verdicts[-1])
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return verdicts, seed


def _verify_row(row, card: dict, sample: int, rng, pool, store) -> RowVerdict:
    section = {**card.get("closed_loop", {}), **card.get("drives", {})}.get(row.key)
    episodes = card["episodes"].get(row.key)
    if section is None or episodes is None:
        return RowVerdict(row.key, 0, 0, 0.0, ("the row is missing from the card",))
    specs = _row_specs(row, card)
    problems = _check_summary(row, section, episodes, [s.trial_id for s in specs])
    if problems:
        return RowVerdict(row.key, len(specs), 0, 0.0, tuple(problems))
    if row.link:
        return RowVerdict(row.key, len(specs), 0, 0.0, note="served over a link: its records are checked, "
                                                           "its episodes not re-run (their timing is the machine's)")
    picks = sorted(rng.sample(range(len(specs)), min(sample, len(specs))))
    t0 = time.perf_counter()
    problems = _rerun(specs, episodes, picks, pool, store)
    return RowVerdict(row.key, len(specs), len(picks), time.perf_counter() - t0, tuple(problems))
