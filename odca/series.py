"""The batched path's view of whole series (``ODCA.run``, training): the runs ODCA makes afresh, which
steps the delta head corrects, and the columns it reads."""

from __future__ import annotations

import numpy as np
import pandas as pd

from racf.odca.gate import DEPTH, DEPTH_UNCONFIRMED

__all__ = ["corrected", "segments"]


def corrected(source: np.ndarray) -> np.ndarray:
    """The steps the head corrects: repairs that rest on a witness. A depth that passed is output
    as it is (Proposition 1), and so is an unconfirmed one: with no witness to measure it
    against, a correction would be a guess (on clean first sights it only moved the depth)."""
    source = np.asarray(source)
    return (source != DEPTH) & (source != DEPTH_UNCONFIRMED)


def segments(df: pd.DataFrame) -> list[np.ndarray]:
    """Row positions of each run ODCA makes afresh: a series, cut where ``slot`` changes."""
    n = len(df)
    if n == 0:
        return []
    new = np.zeros(n, bool)
    new[0] = True
    for name in ("series_id", "slot"):
        if name in df:
            values = df[name].to_numpy()
            new[1:] |= values[1:] != values[:-1]
    starts = np.flatnonzero(new)
    return [np.arange(a, b) for a, b in zip(starts, np.r_[starts[1:], n])]


def _pick(df: pd.DataFrame, name: str, alt: str | None) -> np.ndarray:
    if name in df:
        return df[name].to_numpy(float)
    if alt is not None and alt in df:
        return df[alt].to_numpy(float)
    raise ValueError(f"run(df) needs a {name!r} column" + (f" (or {alt!r})" if alt else "") +
                     f"; got columns {list(df.columns)}")


def _optional(df: pd.DataFrame, name: str, default: float) -> np.ndarray:
    return df[name].to_numpy(float) if name in df else np.full(len(df), default)
