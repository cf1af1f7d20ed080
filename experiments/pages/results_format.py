"""How the results pages write a number: intervals, rates, the provenance line of a stored
result, what a page says where a result is not stored yet, and the stored results of a folder."""

from __future__ import annotations

import json
from pathlib import Path

from racf.stats import ci, num, rate

__all__ = ["NOTE", "page_head", "ci", "num", "rate", "meta_lines", "missing", "stored", "StoredResults"]

NOTE = ("Written by `racf.experiments.pages.results_pages` from the stored results in `docs/results/data/`: every "
        "number is what the command beside it printed, on the code, machine and sensors named. Intervals are "
        "95 %: Wilson for rates, bootstrap for medians and RMSE.")


#: A results page gives the table of contents' width to its tables (the menu stays).
FRONT_MATTER = ["---", "hide:", "  - toc", "---", ""]


def page_head(title: str, *intro: str) -> list[str]:
    """A results page's first lines: its settings, its title, where its numbers come from, and its intro."""
    lines = [*FRONT_MATTER, f"# {title}", "", NOTE, ""]
    for paragraph in intro:
        lines += [paragraph, ""]
    return lines


def meta_lines(meta: dict) -> list[str]:
    """The provenance line of a stored result: its command, commit, version, machine and date."""
    extra = ", ".join(f"{k.replace('_', ' ')} {meta[k]}" for k in ("sensor_profile", "sign_geometry", "detector",
                                                                 "dataset", "draws") if k in meta)
    caveat = (" **Measured on uncommitted changes: no commit reproduces it exactly.**"
              if str(meta["commit"]).endswith("+changes") else "")
    if meta.get("superseded"):  # the code it measured has changed since, and it was not measured again
        caveat += f" **Superseded: {meta['superseded']}.**"
    # A result measured in another checkout of an earlier commit names that commit (its episode code is
    # what ran), and the commit that stored it.
    commit = (f"`{meta['measured_on']}` (stored at `{meta['commit']}`)" if meta.get("measured_on")
              else f"`{meta['commit']}`")
    return [f"*Measured by* `{meta['command']}` *on commit* {commit} (racf {meta['racf']}), "
            f"{meta['machine']}, {meta['measured']}" + (f"; {extra}." if extra else ".") + caveat, ""]


def missing(name: str, command: str) -> list[str]:
    return [f"Not stored yet (`{name}`): run `{command}` and store it with `results_store`.", ""]


def stored(root: Path, name: str, command: str) -> tuple[dict | None, list[str]]:
    """A stored result and the lines that open its section: who measured it where, or (with None)
    that it is not stored yet and the command that makes it."""
    path = Path(root) / f"{name}.json"
    if not path.exists():
        return None, missing(name, command)
    data = json.loads(path.read_text())
    return data, meta_lines(data["meta"])


class StoredResults:
    """The stored results of one folder, loaded on demand."""

    def __init__(self, root: Path):
        self.root = Path(root)

    def __contains__(self, name: str) -> bool:
        return (self.root / f"{name}.json").exists()

    def __getitem__(self, name: str) -> dict:
        return json.loads((self.root / f"{name}.json").read_text())


def emit_json(data: dict, out: Path | None) -> None:
    """A page's data as strict JSON (NaN as null), to ``out`` or printed: what a page's command writes."""
    import math

    text = json.dumps(data, indent=2, allow_nan=False, default=lambda v: None if v is None or
                      (isinstance(v, float) and math.isnan(v)) else float(v))
    if out is None:
        print(text)
    else:
        Path(out).write_text(text + "\n")
