"""What a battery's board says beneath its table, so that the reader need not work it out: on which
commits its cards were measured and what changed between them, and which defences coincide, and why.
"""

from __future__ import annotations

import subprocess
from itertools import combinations

__all__ = ["commit_note", "coincidence_note", "card_commit", "COINCIDENCES"]

#: Why two defences coincide on a battery, where their cards carry no episodes to show it.
COINCIDENCES = {
    ("racf-6", "odca", "vote"): "the vote repairs a stop sign's distance through its existence vote; on the car "
                                "ahead it passes ODCA's distance on unchanged, since its check of the car ahead "
                                "(`lead_check`) is off by default (with it on: the stored result "
                                "`racf-6-vote-lead-check`, on the following results page)",
}

#: The code an episode runs (``provenance.EPISODE_CODE``'s folders), for ``git log`` between two commits.
_EPISODE_PATHS = ("sim", "controllers", "odca", "experiments/episode", "experiments/car", "experiments/link",
                  "experiments/scenarios", "experiments/metrics", "assets")


def card_commit(card: dict) -> str | None:
    """The commit a card was measured on: its own, else its stored result's."""
    return card.get("commit") or (card.get("_meta") or {}).get("commit")


def _changes(old: str, new: str) -> list[str] | None:
    """The commits from ``old`` to ``new`` that changed episode code, newest first (None: git cannot say)."""
    try:
        done = subprocess.run(["git", "log", "--format=%h", f"{old}..{new}", "--", *_EPISODE_PATHS],
                              capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.splitlines() if done.returncode == 0 else None


def _order(commits: list[str]) -> list[str]:
    """The commits oldest first, where git knows them (else as given)."""
    def ahead(a: str, b: str) -> bool:
        done = subprocess.run(["git", "merge-base", "--is-ancestor", a, b], capture_output=True, timeout=20)
        return done.returncode == 0

    try:
        return sorted(commits, key=lambda c: sum(ahead(o, c) for o in commits if o != c))
    except (OSError, subprocess.SubprocessError):
        return commits


def commit_note(cards: list[dict]) -> str:
    """One sentence where a battery's cards come from several commits: which cards each holds, and how
    many commits between them changed the code an episode runs (with the first subjects)."""
    by: dict[str, list[str]] = {}
    for card in cards:
        by.setdefault(card_commit(card) or "unknown", []).append(card["defence"])
    if len(by) < 2:
        return ""
    known = _order([c for c in by if c != "unknown"])
    parts = [f"`{c}` ({', '.join(f'`{d}`' for d in by[c])})" for c in known + (["unknown"] if "unknown" in by else [])]
    text = f"**Measured on {len(by)} commits**: {', '.join(parts)}, oldest first."
    steps = []
    for old, new in zip(known, known[1:]):
        changes = _changes(old, new)
        if changes is None:
            steps.append(f"`git log {old}..{new}` lists what changed from `{old}` to `{new}`")
        elif not changes:
            steps.append(f"from `{old}` to `{new}` no commit changed the code an episode runs, so their cards "
                         "compare as if measured together")
        else:
            listed = ", ".join(f"`{c}`" for c in changes[:4]) + (", ..." if len(changes) > 4 else "")
            steps.append(f"from `{old}` to `{new}`, {len(changes)} commit(s) changed the code an episode runs "
                         f"({listed}; `git log {old}..{new}` says what), so cards on either side may differ by "
                         "the code as well as the defence")
    said = "; ".join(steps)
    return f"{text} {said[0].upper()}{said[1:]}." if said else text


def coincidence_note(cards: list[dict], battery: str, cells) -> str:
    """A sentence for each pair of defences whose every cell on the board is the same value, with why:
    the curated reason (``COINCIDENCES``), else what their carried episodes show."""
    out = []
    for a, b in combinations(cards, 2):
        ca, cb = cells(a), cells(b)
        if not ca or ca != cb:
            continue
        names = tuple(sorted((a["defence"], b["defence"])))
        why = COINCIDENCES.get((battery, *names)) or _episodes_why(a, b)
        out.append(f"`{names[0]}` and `{names[1]}` score the same in every cell: {why}.")
    return " ".join(out)


def _episodes_why(a: dict, b: dict) -> str:
    ea, eb = a.get("episodes"), b.get("episodes")
    if not ea or not eb:
        return ("their cards carry no episodes, so the board cannot tell whether they drove alike or only scored "
                "alike (cards made now carry them)")
    same = all(_outcomes(ea[k]) == _outcomes(eb.get(k)) for k in ea)
    return ("every episode ends the same for both, record for record: on this battery neither does anything the "
            "other does not" if same else "their episodes end differently one by one, but not in any rate the "
                                          "board counts")


#: What names an episode's defence rather than what happened in it.
_IDENTITY = ("trial_id", "setting", "estimator")


def _outcomes(episodes: dict | None) -> list[list] | None:
    if not episodes:
        return None
    keep = [i for i, c in enumerate(episodes["columns"]) if c not in _IDENTITY]
    return [[values[i] for i in keep] for values in episodes["values"]]
