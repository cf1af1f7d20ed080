"""The documentation's reference pages, made from the code so that they cannot drift from it:
the CLI (from the argparse parsers), the registered parts (from the registries) and the step
log (from its one declaration). ``make docs`` writes them (``docs/hooks.py``), and a test
checks that the committed copies are current."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

__all__ = ["cli_markdown", "parts_markdown", "step_log_markdown", "map_markdown", "PAGES", "write_pages",
           "readme_with_table", "write_readme"]


def cli_markdown() -> str:
    """Every ``racf`` command with its help and flags, as ``racf COMMAND --help`` prints them."""
    from racf.experiments.cli import build_parser

    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal: the page must not depend on it
    try:
        return _cli_markdown(build_parser())
    finally:
        if saved is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = saved


def _cli_markdown(parser: argparse.ArgumentParser) -> str:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {a.dest: a.help for a in sub._choices_actions}
    lines = ["# The `racf` command line", "",
             "Made from the argparse parsers (`racf COMMAND --help` prints the same). Every command "
             "that runs episodes takes `--plugin FILE.py`.", ""]
    from racf.experiments.cli.groups import GROUPS

    for name in helps:  # the commands --help lists, in its order; a group's commands under it
        command = sub.choices[name]
        command.prog = f"racf {name}"
        lines += [f"## `racf {name}`", "", helps.get(name) or "", "", "```text", command.format_help().rstrip(), "```",
                  ""]
        if name in GROUPS:
            inner = next(a for a in command._actions if isinstance(a, argparse._SubParsersAction))
            inner_helps = {a.dest: a.help for a in inner._choices_actions}
            for short, parser in inner.choices.items():
                lines += [f"### `racf {name} {short}`", "", inner_helps.get(short) or "", "", "```text",
                          parser.format_help().rstrip(), "```", ""]
    aliases = [f"`racf {flat}` = `racf {group} {short}`" for group, (_, commands) in GROUPS.items()
               for short, flat in commands.items()]
    lines += ["## Old names", "", "The commands had flat names before they were grouped; those names still work "
              "(scripts run unchanged) and `racf bench` with the offline benchmark's flags after it is that benchmark: "
              + "; ".join(aliases) + ".", ""]
    from racf.experiments.cli.mistakes import mistakes_markdown

    return "\n".join([*lines, mistakes_markdown(), ""])


def parts_markdown() -> str:
    """The registered attacks, estimators, detectors, scenarios and metrics with what each does."""
    from racf.experiments.cli.common import registry_markdown

    return "\n".join(["# The registered parts", "",
                      "racf's own attacks, estimators (defences), detectors, scenarios and metrics, read from the "
                      "registries "
                      "(`racf list --markdown` prints the same; a plug-in you install or load joins them).", "",
                      registry_markdown()])


def step_log_markdown() -> str:
    """The step log's columns from their one declaration, and the result row's fields."""

    from racf.experiments.episode.record import STEP_COLUMNS
    from racf.experiments.episode.runner import IDENTITY
    from racf.plugins import CAR_STAGES, METRICS

    lines = ["# The step log and the result row", "",
             "Every episode logs one row per 50 Hz step with these columns "
             "(`racf.experiments.episode.record.STEP_COLUMNS`), then whatever the estimator reports "
             "in `diagnostics()`. *car*: made by the car's software from its observations and the "
             "map; *referee*: ground truth, never seen by the car.", "",
             "| column | unit | side | meaning |", "|---|---|---|---|"]
    lines += [f"| `{c.name}` | {c.unit or '-'} | {c.side} | {c.meaning} |" for c in STEP_COLUMNS]
    lines += ["", "## The car stages' columns", "",
              "A car stage a mission engages (`racf.car_stages`: `Mission.stages`) adds the columns it declares "
              "(`CarStage.columns`), on the car's side, after those above; an episode without it has none of them. "
              "racf's own:", "", "| column | unit | stage | meaning |", "|---|---|---|---|"]
    for name in (n for n in CAR_STAGES if CAR_STAGES.plugin(n).builtin):
        lines += [f"| `{c.name}` | {c.unit or '-'} | `{name}` | {c.meaning} |" for c in CAR_STAGES[name].columns]
    lines += ["", "## The result row", "",
              "`TrialResult`, strict JSON (null for a missing number): which episode it is ("
              + ", ".join(f"`{name}`" for name in IDENTITY) + "), then the fields of each metric the episode "
              "scored (`racf.plugins.METRICS`; racf's own are listed here, a plug-in's after them):", "",
              "| field | unit | metric | summarised as | meaning |", "|---|---|---|---|---|"]
    for name in sorted((n for n in METRICS if METRICS.plugin(n).builtin), key=lambda n: (METRICS[n].order, n)):
        lines += [f"| `{f.name}` | {f.unit or '-'} | `{name}` | {f.summary or '-'} | {f.meaning} |"
                  for f in METRICS[name].fields]
    lines.append("")
    return "\n".join(lines)


def battery_markdown() -> str:
    """Every released scorecard battery, row by row, from its one declaration."""
    from racf.experiments.scorecard.battery import BATTERIES, PENALTIES

    lines = ["# The scorecard's batteries", "",
             "Written from `racf.experiments.scorecard.battery.BATTERIES`. A released battery never changes: "
             "a change is a new name. `--quick` runs every row at its quick N.", ""]
    for name, battery in BATTERIES.items():
        lines += [f"## `{name}`", "", f"The car's stop-sign detector: `{battery.detector}`, unless a row says otherwise.",
                  "", "| row | what | N | quick N | attacked |", "|---|---|---|---|---|"]
        lines += [f"| `{r.key}` | {r.title} | {r.n} | {r.n_quick} | {'yes' if r.attacked else 'no'} |"
                  for r in battery.rows()]
        offline = (f"Offline: presets {', '.join(battery.offline_presets)} on the `{battery.offline_split}` test "
                   f"drives, {battery.offline_draws} corruption draws ({battery.offline_draws_quick} quick); the strong "
                   "RMSE also as a ratio to Chronos-only's." if battery.offline_presets else
                   "Offline: none (the battery rates the closed loop only).")
        lines += ["", f"{offline} Detection: from every closed-loop row's step logs. Cost: trainable parameters and "
                      "the per-step time. Driving score: every row the criteria judge, and the drives. Penalties: "
                      + ", ".join(f"{k.replace('_', ' ')} x {v}" for k, v in PENALTIES.items()) + ".", ""]
    return "\n".join(lines)


def map_markdown() -> str:
    """The map's bodies as the model holds them: name, pose, geoms, and each kind's frame."""
    import math

    import numpy as np

    from racf.sim.world.scene import load_model
    from racf.sim.world.stop_signs import PLATE_IN_SCAN

    model = load_model()
    lines = ["# The map's bodies", "",
             "Read from the model the env builds (`racf.sim.world.scene.load_model()`, default sign geometry). A "
             "world manager moves, turns or hides these bodies by name (`model.body(NAME)`; the names come from "
             "`racf.sim.world.scene.sign_body(i)` and `obstacle_body(i)`), and the referee's truth moves with them "
             "(`racf.sim.env.truth`). Map frame: x east, y north, z up, metres; yaw counter-clockwise from +x.", "",
             "Frames: a stop sign's body stands at the foot of its pole, its x axis the plate's face normal (the "
             "direction the face looks), z up; the plate's centre is at (0, 0, "
             f"{PLATE_IN_SCAN.centre_height_m:g}) m in it with the default geometry, the pole just behind it "
             "(negative x). A crate's body is its centre on the floor, x along the lane. The car's body "
             "(`qcar`) has x forward, y left; its camera is `d435`, its LiDAR the site `lidar`.", "",
             "| body | x m | y m | yaw deg | geoms |", "|---|---|---|---|---|"]
    for body in range(1, model.nbody):
        if model.body_parentid[body] != 0:
            continue
        w, _, _, z = model.body_quat[body]
        yaw = math.degrees(2 * math.atan2(z, w))
        x, y, _ = np.round(model.body_pos[body], 3)
        lines.append(f"| `{model.body(body).name}` | {x:g} | {y:g} | {yaw:.1f} | {int(model.body_geomnum[body])} |")
    return "\n".join([*lines, ""])


#: The generated pages, relative to ``docs/``.
PAGES = {"reference/cli.md": cli_markdown, "reference/parts.md": parts_markdown,
         "reference/step-log.md": step_log_markdown, "reference/battery.md": battery_markdown,
         "reference/map.md": map_markdown}


#: The docs folder of the checkout (the results data lives there, not in the package).
_DOCS = Path(__file__).resolve().parents[2] / "docs"


def _results_pages() -> None:
    from racf.experiments.pages.results_pages import RESULT_PAGES

    for name, make in RESULT_PAGES.items():
        PAGES[name] = (lambda make: lambda: make(_DOCS / "results" / "data"))(make)


_results_pages()
#: The stored cards' pages: a folder written whole from the stored results (a page whose card is gone goes).
CARD_FOLDER = "results/cards"


def _card_pages() -> None:
    from racf.experiments.pages.leaderboard_page import card_pages

    for name, make in card_pages(_DOCS / "results" / "data").items():
        PAGES[f"results/{name}"] = make


_card_pages()


def _board_js() -> str:
    from racf.experiments.scorecard.board import BOARD_JS

    return BOARD_JS.read_text()


#: The board's sorting script, kept once in the package (a scorecard's page inlines it).
PAGES["javascripts/board.js"] = _board_js
#: The changelog is kept once, at the top of the repository; the site shows that file.
PAGES["changelog.md"] = lambda: (_DOCS.parent / "CHANGELOG.md").read_text()


def write_pages(docs: Path) -> list[Path]:
    """Writes every generated page under ``docs`` (only where it changed); returns them."""
    out = []
    for name, make in PAGES.items():
        path = Path(docs) / name
        text = make()
        if not path.exists() or path.read_text() != text:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
        out.append(path)
    for stale in sorted((Path(docs) / CARD_FOLDER).glob("*.md")):
        if f"{CARD_FOLDER}/{stale.name}" not in PAGES:
            stale.unlink()
    return out


#: The README's headline table sits between these lines; the docs build rewrites what is between.
README_MARKERS = ("<!-- results table: written from docs/results/data by `make docs` -->", "<!-- end of results table -->")


def readme_with_table(text: str) -> str:
    """The README's text with its headline table written afresh from the stored results."""
    from racf.experiments.pages.results_pages import readme_table

    begin, end = README_MARKERS
    if begin not in text or end not in text:
        raise ValueError(f"the README has lost its results-table markers: {begin} ... {end}")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    return f"{head}{begin}\n{readme_table(_DOCS / 'results' / 'data')}\n{end}{tail}"


def write_readme(readme: Path) -> None:
    """Rewrites the README's headline table where it changed."""
    text = Path(readme).read_text()
    new = readme_with_table(text)
    if new != text:
        Path(readme).write_text(new)
