"""What a card carries so that anyone can check it: every episode's result record and a digest of
its step log, row by row (``card["episodes"]``).

A card's rates are summaries of its episodes. With the records on the card, a checker can sum
them up again (a rate changed by hand no longer matches its episodes), and with the step logs'
digests it can re-run any episode and require the same record and the same log to the bit
(``racf board verify``: :mod:`racf.experiments.scorecard.verify`). Episode ids name the spec,
the configs and the code, so a record also says what made it.

Only what the wall clock measures (a served defence's round-trip times) is left out of both:
two machines never time a network alike.
"""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pandas as pd

__all__ = ["WALL_CLOCK", "card_episodes", "episode_frame", "record_of", "log_digest"]

#: Columns the wall clock measures (result rows and step logs): never required to reproduce.
WALL_CLOCK = frozenset({"service_rtt_p50_ms", "service_rtt_p99_ms", "service_rtt_ms"})


def _plain(value):
    """A JSON value for one cell: Python's own types, null for NaN, a missing value or infinity."""
    if hasattr(value, "item") and not isinstance(value, (list, dict, str, bytes)):
        value = value.item()  # numpy scalars
    if value is None or value is pd.NA or value is pd.NaT:
        return None
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def record_of(row: dict) -> dict:
    """One episode's result row as the card holds it: JSON values, the wall clock's columns left out."""
    return {k: _plain(v) for k, v in row.items() if k not in WALL_CLOCK}


def log_digest(log: pd.DataFrame | None) -> str | None:
    """SHA-256 of a step log's columns and values (row order included; the wall clock's columns left
    out): the same episode run again gives the same digest. None for an episode without a log."""
    if log is None:
        return None
    h = hashlib.sha256()
    for name in log.columns:
        if name in WALL_CLOCK:
            continue
        values = log[name].to_numpy()
        h.update(f"{name}:{log[name].dtype}:".encode())
        if values.dtype == object:  # strings, None, or arrays per step (the LiDAR's field of view)
            for cell in values:
                h.update(cell.tobytes() if isinstance(cell, np.ndarray) else repr(cell).encode())
                h.update(b"\x00")
        else:
            h.update(np.ascontiguousarray(values).tobytes())
    return h.hexdigest()


def card_episodes(frame: pd.DataFrame, logs: list[pd.DataFrame | None]) -> dict:
    """A row's episodes as a card carries them: the columns once, one list of values per episode (in
    the row's order) and one log digest per episode."""
    records = [record_of(r) for r in frame.to_dict("records")]
    columns = list(records[0]) if records else []
    return {"columns": columns, "values": [[r.get(c) for c in columns] for r in records],
            "log_sha256": [log_digest(log) for log in logs]}


def episode_frame(episodes: dict) -> pd.DataFrame:
    """The result rows a card's ``episodes`` entry holds, as the summaries read them."""
    return pd.DataFrame(episodes["values"], columns=episodes["columns"])
