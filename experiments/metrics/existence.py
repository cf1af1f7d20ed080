"""Whether the car stopped where a sign stands, and only there (the ``existence`` metric).

SCR at real signs is the outcome metric's ``success``. Where no real sign stands (the map's
sign was removed; a phantom picture stands in its place) the right thing is to drive on, and
a **needless stop** is the car braking to rest on the approach: a stop no sign asked for.
It is the ``no_needless_stop`` criterion failed (``racf.experiments.episode.criteria``), scored
where the referee's log says no sign stands (``sign_stands``), from the car's own brake command
and the body's speed. The driving score is the ``criteria`` metric's.
"""

from __future__ import annotations

from racf.experiments.episode.criteria import NEEDLESS_STOP_PENALTY, NoNeedlessStop
from racf.experiments.metrics.base import Episode, Field, Metric

__all__ = ["Existence", "NEEDLESS_STOP_PENALTY"]


class Existence(Metric):
    """Needless stops where no sign stands."""

    name = "existence"
    meaning = "whether a real sign stood, and needless stops where none did"
    order = 70
    higher_is_better = {"needless_stop": False}
    fields = (
        Field("sign_stands", None, "", "a real sign stood at the target (False: removed, or a phantom)"),
        Field("needless_stop", None, "", "no real sign stood and the car braked to rest (None where one stood)",
              summary="rate"),
    )

    def score(self, episode: Episode) -> dict:
        rule = NoNeedlessStop()
        if not rule.applies(episode):
            return {"sign_stands": True}
        return {"sign_stands": False, "needless_stop": not rule.passed(episode)}
