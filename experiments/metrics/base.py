"""What a metric is: a measure of one episode, declared once and summarised over many.

A metric declares its result fields (:class:`Field`: name, unit, meaning, the value where it
does not apply, and how it is summarised over episodes), scores one episode from its per-step
log and plan (:meth:`Metric.score`), and says what its summary over a setting's episodes is
(:meth:`Metric.summarize`: by default, per field, a rate with its Wilson interval or a median
with its bootstrap interval). The result row (``TrialResult``), the sweep summary and report,
the scorecard's closed-loop rows and the step-log reference read these declarations.

A metric registers under the entry-point group ``racf.metrics`` (or is loaded with
``--plugin FILE.py``), racf's own the same way as a user's. Metrics with ``always = True`` score
every episode; the others score the episodes whose spec (``TrialSpec.metrics``) or scenario
(``Scenario.metrics``) asks for them.
"""

from __future__ import annotations

from typing import Any, ClassVar

import pandas as pd

from racf.experiments.episode.fields import SUMMARIES, Field
from racf.experiments.episode.runner import Episode
from racf.stats import median_ci, wilson_interval

__all__ = ["Field", "Metric", "Episode", "SUMMARIES", "summarize_fields"]


class Metric:
    """A measure of one episode. Subclass it, declare ``name`` and ``fields``, write :meth:`score`.

    Attributes:
        name: its key (``racf list``, ``TrialSpec.metrics``, ``--metric``).
        meaning: one line for ``racf list``.
        fields: the result columns it fills.
        always: scored on every episode (else only where a spec or its scenario asks).
        order: where its columns stand in the result row (racf's own: 10-60; a plug-in: 100).
        higher_is_better: per summarised field, which way is better (the scorecard's comparisons).
        needs_criterion: the criterion it measures (``Criterion.name``): it scores, and is summarised
            over, only the episodes whose scenario judges that criterion (racf's stop-sign measures
            need ``stop_rule``: a scenario judged otherwise carries none of their fields). None: every one.
    """

    name: ClassVar[str] = "metric"
    #: Marks the base of racf's metrics for the registries (``racf.plugins.PART_KIND``).
    racf_part: ClassVar[str] = "metric"
    meaning: ClassVar[str] = ""
    fields: ClassVar[tuple[Field, ...]] = ()
    always: ClassVar[bool] = False
    order: ClassVar[int] = 100
    higher_is_better: ClassVar[dict[str, bool]] = {}
    needs_criterion: ClassVar[str | None] = None

    @classmethod
    def applies_to(cls, scenario) -> bool:
        """Whether it measures the episodes of ``scenario`` (a ``Scenario`` class or instance)."""
        return cls.needs_criterion is None or any(c.name == cls.needs_criterion for c in scenario.criteria)

    def score(self, episode: Episode) -> dict[str, Any]:
        """The fields' values for one episode (a field left out takes its default)."""
        raise NotImplementedError

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict[str, Any]:
        """The summary of a setting's result rows (``attacked``: the setting runs an attack).
        By default each field with a ``summary``: ``rate``: ``{name}_rate``, ``{name}_rate_ci`` and
        ``n_{name}``; ``median``: ``{name}_median``, ``{name}_ci`` and ``n_{name}``. Rows where the
        field is missing (None, NaN) do not count."""
        return summarize_fields(self.fields, results)

    @classmethod
    def defaults(cls) -> dict[str, Any]:
        return {f.name: f.default for f in cls.fields}


def summarize_fields(fields, results: pd.DataFrame) -> dict[str, Any]:
    """Each field with a ``summary`` over the rows that hold it: ``rate``: ``{name}_rate``,
    ``{name}_rate_ci`` (Wilson) and ``n_{name}``; ``median``: ``{name}_median``, ``{name}_ci``
    (bootstrap) and ``n_{name}``. Rows where the field is missing (None, NaN) do not count."""
    out: dict[str, Any] = {}
    for field in fields:
        if field.summary is None or field.name not in results:
            continue
        column = results[field.name]
        if field.summary == "rate":
            values = column.dropna().astype(bool)
            k, n = int(values.sum()), int(len(values))
            out |= {f"n_{field.name}": n, f"{field.name}_rate": k / n if n else None,
                    f"{field.name}_rate_ci": list(wilson_interval(k, n))}
        else:
            values = pd.to_numeric(column, errors="coerce").dropna()
            median, interval = median_ci(values)
            out |= {f"n_{field.name}": int(len(values)), f"{field.name}_median": median,
                    f"{field.name}_ci": interval}
    return out
