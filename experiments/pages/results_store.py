"""Stores a measurement for the results pages: what a command printed (``--json``) or wrote (a
sweep's ``summary.json`` and the report's other JSON files), under ``docs/results/data/NAME.json``
with what produced it: the command, the commit, racf's version, the date and the machine.

    python -m racf.experiments.pages.results_store NAME SOURCE [SOURCE ...] --command "racf ..."

A SOURCE is a JSON file, or a sweep's folder (its ``summary.json`` becomes ``settings``, and every
other ``NAME.json`` the report wrote but ``sweep.json``, such as ``stealth.json``, ``recall.json`` or
a scenario's own, becomes ``NAME``). Several sources are merged key by key, in order. The
pages are then rewritten by ``make docs`` (``racf.experiments.pages.results_pages``).
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import sys
from pathlib import Path

from racf import __version__
from racf.provenance import atomic_write, commit, machine

__all__ = ["DATA_DIR", "machine", "commit", "load_source", "store_result", "main"]

#: Where the results pages read their data (the repository's docs, not an installed copy).
DATA_DIR = Path("docs/results/data")


def load_source(path: Path) -> dict:
    """One source as a dict: a JSON object, or a sweep's folder."""
    if path.is_dir():
        summary = path / "summary.json"
        if not summary.exists():
            raise ValueError(f"{path} is a folder without summary.json; give a sweep's folder or a JSON file")
        data = {"settings": json.loads(summary.read_text())}
        for part in sorted(path.glob("*.json")):  # the report's other files (stealth, recall, a scenario's own)
            if part.stem not in ("summary", "sweep"):
                data[part.stem] = json.loads(part.read_text())
        return data
    try:
        data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as err:
        raise ValueError(f"cannot read {path} as JSON ({err})") from err
    if not isinstance(data, dict):
        raise ValueError(f"{path} holds a JSON {type(data).__name__}; a result is a JSON object")
    return data


def store_result(name: str, payload: dict, *, command: str, data_dir: Path = DATA_DIR, force: bool = False,
                 **extra) -> Path:
    """Writes ``data_dir/NAME.json``: ``{"meta": {...}, **payload}`` as strict JSON.

    A result is identified by the commit that made it, so one measured on a tree whose tracked
    code differs from its commit (``+changes``) is refused: no commit reproduces it. ``force``
    stores it all the same, marked ``"uncommitted": true`` (the pages say so)."""
    if not name.replace("-", "").isalnum():
        raise ValueError(f"name {name!r}: use letters, digits and '-'")
    made_by = commit()
    if made_by.endswith("+changes") and not force:
        raise ValueError(f"the checkout's tracked code differs from its commit ({made_by}): no commit would "
                         f"reproduce {name!r}. Commit, measure again, then store (or pass --force-uncommitted to "
                         f"store it marked as uncommitted)")
    meta = {"commit": made_by, "racf": __version__, "measured": dt.date.today().isoformat(),
            "machine": machine(), "command": command, **extra}
    if made_by.endswith("+changes"):
        meta["uncommitted"] = True
    Path(data_dir).mkdir(parents=True, exist_ok=True)
    return atomic_write(Path(data_dir) / f"{name}.json",
                        json.dumps({"meta": meta, **payload}, indent=1, allow_nan=False) + "\n")


def _meta_pair(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"--meta takes KEY=VALUE, got {text!r}")
    return key, value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m racf.experiments.pages.results_store",
                                     description="store a measurement for the results pages")
    parser.add_argument("name", help="the result's name (docs/results/data/NAME.json)")
    parser.add_argument("sources", nargs="+", type=Path, help="JSON files or sweep folders, merged in order")
    parser.add_argument("--command", required=True, help="the command that produced it, as a user would type it")
    parser.add_argument("--meta", type=_meta_pair, action="append", default=[], metavar="KEY=VALUE",
                        help="more facts for the page (sensor_profile=qcar2, detector=learned, ...)")
    parser.add_argument("--under", metavar="KEY", help="nest each source under KEY (for a command's bare --json)")
    parser.add_argument("--data-dir", type=Path, default=DATA_DIR, help=f"where to store (default {DATA_DIR})")
    parser.add_argument("--force-uncommitted", action="store_true",
                        help="store a result measured on a tree with uncommitted changes to tracked code, marked so "
                             "(refused without it)")
    args = parser.parse_args(argv)
    try:
        payload: dict = {}
        for source in args.sources:
            data = load_source(source)
            payload.update({args.under: data} if args.under else data)
        path = store_result(args.name, payload, command=args.command, data_dir=args.data_dir,
                            force=args.force_uncommitted, **dict(args.meta))
    except ValueError as err:
        print(f"results_store: {err}", file=sys.stderr)
        return 2
    print(f"stored {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
