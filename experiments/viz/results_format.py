"""How the results pages write a number: intervals, rates, the provenance line of a stored
result, and what a page says where a result is not stored yet."""

from __future__ import annotations

__all__ = ["NOTE", "page_head", "ci", "num", "rate", "meta_lines", "missing"]

NOTE = ("Written by `racf.experiments.viz.results_pages` from the stored results in `docs/results/data/`: every "
        "number is what the command beside it printed, on the code, machine and sensors named. Intervals are "
        "95 %: Wilson for rates, bootstrap for medians and RMSE.")


def page_head(title: str, *intro: str) -> list[str]:
    """A results page's first lines: its title, where its numbers come from, and its intro."""
    lines = [f"# {title}", "", NOTE, ""]
    for paragraph in intro:
        lines += [paragraph, ""]
    return lines


def ci(pair, digits: int = 2) -> str:
    """``[lo, hi]``, or nothing where the interval is undefined."""
    return "" if not pair or pair[0] is None else f"[{pair[0]:.{digits}f}, {pair[1]:.{digits}f}]"


def num(value, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def rate(value, pair, digits: int = 2) -> str:
    """A value with its interval (``-`` where there is none)."""
    return "-" if value is None else f"{value:.{digits}f} {ci(pair, digits)}".strip()


def meta_lines(meta: dict) -> list[str]:
    """The provenance line of a stored result: its command, commit, version, machine and date."""
    extra = ", ".join(f"{k.replace('_', ' ')} {meta[k]}" for k in ("sensor_profile", "sign_geometry", "detector",
                                                                 "dataset", "draws") if k in meta)
    caveat = (" **Measured on uncommitted changes: no commit reproduces it exactly.**"
              if str(meta["commit"]).endswith("+changes") else "")
    return [f"*Measured by* `{meta['command']}` *on commit* `{meta['commit']}` (racf {meta['racf']}), "
            f"{meta['machine']}, {meta['measured']}" + (f"; {extra}." if extra else ".") + caveat, ""]


def missing(name: str, command: str) -> list[str]:
    return [f"Not stored yet (`{name}`): run `{command}` and store it with `results_store`.", ""]
