"""A result row's field, declared once: what metrics and criteria fill and summaries read."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["Field", "SUMMARIES"]

#: How a field is summarised over episodes: ``rate`` (a share of true values, Wilson interval),
#: ``median`` (bootstrap interval), None (not summarised by default).
SUMMARIES = ("rate", "median", None)


@dataclass(frozen=True)
class Field:
    """One column of the result row.

    Attributes:
        name: the column.
        default: its value where the metric does not apply (NaN, None, False, 0).
        unit: what a number counts (``m``, ``s``, ``frames``); empty for flags and labels.
        meaning: one line for the docs.
        summary: how :meth:`Metric.summarize` summarises it by default (``SUMMARIES``).
    """

    name: str
    default: Any = math.nan
    unit: str = ""
    meaning: str = ""
    summary: str | None = None
