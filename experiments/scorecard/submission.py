"""Putting a card on the leaderboard: what a submission holds, and the check it must pass.

A submission is one JSON file, ``docs/results/submissions/<battery>-<defence>.json``:

- ``card``: the card as ``racf scorecard --json`` wrote it (its code version, the commit it was
  measured on, every row of its battery at full N);
- ``code``: where the defence's code is (a package on PyPI, a repository at a commit, or a file in
  racf's own tree);
- ``command``: the command that measured it, so that anyone can measure it again;
- ``submitted``: the date;
- ``verified``: how ``racf board verify`` checked it (the sample of episodes re-run per row, its seed).

``racf board check CARD.json`` says whether a card may go on the board; ``racf board verify``
measures it again; ``racf board submit`` writes the submission after both, and the board's page (``make docs``) sets every submitted
card beside racf's own.
"""

from __future__ import annotations

import datetime as _dt
import json
import re
from dataclasses import dataclass
from pathlib import Path

from racf.errors import UserError

__all__ = ["card_problems", "load_card", "Submission", "load_submissions", "SUBMISSIONS"]

#: Where the submitted cards live in racf's checkout (the board's page reads them from there).
SUBMISSIONS = Path("docs/results/submissions")
_VERSION = re.compile(r"^racf \S+, code [0-9a-f]{12}$")


def load_card(path: str | Path) -> dict:
    """A card file, strictly: one line naming what is wrong if it is not one."""
    path = Path(path)
    try:
        card = json.loads(path.read_text(), parse_constant=_no_constant)
    except OSError as err:
        raise UserError(f"cannot read the card {path}: {err.strerror or err}") from None
    except (json.JSONDecodeError, ValueError) as err:
        raise UserError(f"{path} is not a card: {err}") from None
    if isinstance(card, dict) and isinstance(card.get("cards"), list) and len(card["cards"]) == 1:
        card = card["cards"][0]  # `racf scorecard --json` of one defence
    elif isinstance(card, dict) and isinstance(card.get("card"), dict) and "command" in card:
        card = card["card"]  # a submission file
    if not isinstance(card, dict) or not {"defence", "battery", "closed_loop"} <= set(card):
        raise UserError(f"{path} is not a card: it has no defence, battery and closed_loop (give the file "
                        "`racf scorecard --defence NAME --json` printed, or one under OUT/cards/)")
    return card


def _no_constant(name: str):
    raise ValueError(f"it holds {name}, and a card is strict JSON (null, never NaN)")


def card_problems(card: dict) -> list[str]:
    """What keeps a card off the board (empty: none): a quick or unknown battery, a row missing or
    short of its N, no offline rows where the battery has them, a version or commit that does not
    name the code, or a tree with uncommitted changes."""
    from racf.experiments.scorecard.battery import BATTERIES

    problems = []
    if card.get("quick") or str(card.get("battery", "")).endswith("-quick"):
        problems.append("it is a quick card (small N): run it without --quick")
    battery = BATTERIES.get(str(card.get("battery", "")).removesuffix("-quick"))
    if battery is None:
        return problems + [f"its battery {card.get('battery')!r} is none of racf's ({', '.join(BATTERIES)})"]
    rows = {**card.get("closed_loop", {}), **card.get("drives", {})}
    for row in battery.rows():
        got = rows.get(row.key)
        if got is None:
            problems.append(f"row {row.key!r} is missing")
        elif got.get("n") != row.n:
            problems.append(f"row {row.key!r} has N {got.get('n')}, the battery's is {row.n}")
    if battery.offline_presets and not card.get("offline"):
        problems.append("the offline rows are missing (the battery rates the distance offline too)")
    if not _VERSION.match(str(card.get("version", ""))):
        problems.append(f"its version {card.get('version')!r} names no code digest")
    commit = str(card.get("commit", ""))
    if not re.fullmatch(r"[0-9a-f]{7,40}", commit):
        problems.append("it was measured on uncommitted changes: commit them and card it again" if "+changes" in commit
                        else "it names no commit (cards made before racf recorded one: card it again)")
    return problems


@dataclass(frozen=True)
class Submission:
    """A card with what it takes to measure it again."""

    card: dict
    code: str
    command: str
    submitted: str
    #: How ``racf board verify`` checked it: the sample per row, its seed, the episodes re-run.
    verified: dict | None = None

    @property
    def file_name(self) -> str:
        return f"{self.card['battery']}-{self.card['defence']}.json"

    def to_json(self) -> str:
        return json.dumps({"card": self.card, "code": self.code, "command": self.command,
                           "submitted": self.submitted, "verified": self.verified}, indent=1, allow_nan=False, sort_keys=True) + "\n"

    @classmethod
    def make(cls, card: dict, code: str, command: str, taken: set[str] = frozenset(),
             verified: dict | None = None) -> "Submission":
        """A submission of ``card``; UserError naming every problem (``card_problems``, an empty code or
        command, a name that a built-in defence already has on the board)."""
        problems = card_problems(card)
        if not code.strip():
            problems.append("--code is empty: say where the defence's code is (a package, a repository at a commit)")
        if not command.strip().startswith("racf scorecard"):
            problems.append("--command must be the `racf scorecard ...` command that measured it")
        if card.get("defence") in taken:
            problems.append(f"the board already has a defence named {card.get('defence')!r}: register yours under "
                            "another name")
        if problems:
            raise UserError(f"the card of {card.get('defence')!r} cannot go on the board: " + "; ".join(problems))
        return cls(card, code.strip(), command.strip(), _dt.date.today().isoformat(), verified)


def load_submissions(folder: str | Path) -> list[Submission]:
    """Every submission in ``folder`` (none if it does not exist), in name order."""
    out = []
    for path in sorted(Path(folder).glob("*.json")):
        data = json.loads(path.read_text())
        out.append(Submission(data["card"], data["code"], data["command"], data["submitted"], data.get("verified")))
    return out
