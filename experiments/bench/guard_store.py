"""Where the speed guard keeps its ratio: ``docs/results/data/speed-guard.json``, one entry per
commit (the newest is the one ``make check-speed`` compares with)."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

from racf.errors import UserError
from racf.provenance import atomic_write

__all__ = ["GUARD_FILE", "load_guard", "store_guard"]

GUARD_FILE = Path("docs/results/data/speed-guard.json")


def load_guard(path: Path = GUARD_FILE) -> dict | None:
    """The newest stored entry ({commit, ratio, ...}), or None."""
    if not path.exists():
        return None
    entries = json.loads(path.read_text()).get("history", [])
    return entries[-1] if entries else None


def store_guard(result, path: Path = GUARD_FILE) -> str:
    """Appends this commit's ratio (a commit measured again replaces its entry); refuses a tree
    whose tracked code differs from its commit (no commit would reproduce it)."""
    from racf.provenance import commit, machine
    from racf import __version__

    made_by = commit()
    if made_by.endswith("+changes"):
        raise UserError(f"the checkout's tracked code differs from its commit ({made_by}): commit, then store")
    data = json.loads(path.read_text()) if path.exists() else {}
    history = [e for e in data.get("history", []) if e["commit"] != made_by]
    history.append({"commit": made_by, "racf": __version__, "measured": dt.date.today().isoformat(),
                    "machine": machine(), **result.to_dict()})
    meta = {"commit": made_by, "racf": __version__, "measured": dt.date.today().isoformat(), "machine": machine(),
            "command": "racf bench guard --store"}
    atomic_write(path, json.dumps({"meta": meta, "history": history}, indent=1, allow_nan=False) + "\n")
    return str(path)
