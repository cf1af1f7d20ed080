"""Metrics: measures of one episode, as plug-ins (``racf.metrics``).

:class:`Metric` and :class:`Field` are what a user's metric is made of; racf's own
(:mod:`~racf.experiments.metrics.builtin`) register the same way. ``racf.plugins.METRICS`` holds
them by name.
"""

from racf.experiments.metrics.base import SUMMARIES, Episode, Field, Metric

__all__ = ["Episode", "Field", "Metric", "SUMMARIES"]
