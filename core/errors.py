"""What can go wrong that is not racf's own bug, as three exception families the command line
turns into one line each (``racf.experiments.cli.main``):

=====================  ======================================================  =========
family                 what it means                                           exit code
=====================  ======================================================  =========
:class:`UserError`     something a user gave cannot be used: a path, a value,  2
                       a spec, a plug-in, a checkpoint, a dataset, a
                       recording or an output folder. Raised where it is
                       found, before any episode runs.
:class:`EpisodeFailed` a user's code raised inside episodes (or a worker       1
                       died twice on one): the finished episodes are stored,
                       the tracebacks are in a log under the results folder.
:class:`Interrupted`   Ctrl-C or SIGTERM stopped a batch: what is stored is    130
                       kept, and the same command resumes it.
=====================  ======================================================  =========

The module imports nothing of racf's: every package may raise these.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["UserError", "EpisodeFailed", "Interrupted", "Failure"]


class UserError(ValueError):
    """Something a user gave that racf cannot use; the message names what is wrong and what is
    allowed. A ValueError, so library callers that catch those keep working."""


@dataclass(frozen=True)
class Failure:
    """One episode that did not finish.

    Attributes:
        episode: the episode's id.
        where: what raised: ``estimator plug-in 'name'``, ``attack 'name'``, ``racf`` (a bug of
            racf's own) or ``worker process`` (it died).
        error: ``ExceptionType: message``.
        traceback: the full traceback text (or what is known of a dead worker).
        spec: the episode's spec in words (setting, sign, speed, seed).
    """

    episode: str
    where: str
    error: str
    traceback: str
    spec: str


class EpisodeFailed(RuntimeError):
    """Episodes of a batch did not finish; every other episode is stored.

    Args:
        failures: what failed, in the order it did.
        stored: episodes of the batch now stored.
        total: episodes in the batch.
        log: the file holding every failure's traceback.
    """

    def __init__(self, failures: list[Failure], stored: int, total: int, log: Path) -> None:
        self.failures, self.stored, self.total, self.log = failures, stored, total, Path(log)
        first = failures[0]
        more = f" (and {len(failures) - 1} more)" if len(failures) > 1 else ""
        super().__init__(f"{len(failures)} of {total} episodes failed: {first.where} raised {first.error} in "
                         f"episode {first.spec}{more}; {stored} of {total} stored; tracebacks in {self.log}")


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM stopped a batch after ``stored`` of its ``total`` episodes were stored
    (``total`` None: a search, whose size is its budget, not a count of episodes)."""

    def __init__(self, stored: int, total: int | None) -> None:
        self.stored, self.total = stored, total
        what = f"{stored} of {total} episodes stored" if total is not None else f"{stored} episodes stored"
        super().__init__(f"interrupted: {what}; run the same command again to resume")
