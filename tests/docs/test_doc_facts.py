"""What the pages say of racf's parts is what the registries hold: a list of racf's own scenarios or
metrics names every one, a count in words is the count, and every ``racf COMMAND`` a page names is a
command the CLI has (a grouped one under its group)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from racf.plugins import REGISTRIES

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
#: Pages written by hand (the generated ones are made from the code; the changelog is history).
HAND = [p for p in PAGES if p.name != "changelog.md" and "reference" not in p.parts and "results" not in p.parts]
WORDS = {"two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9, "ten": 10,
         "eleven": 11, "twelve": 12}
KINDS = {"scenarios": "scenario", "metrics": "metric", "attacks": "attack", "estimators": "estimator",
         "detectors": "detector"}


def _own(kind: str) -> set[str]:
    registry = REGISTRIES[kind]
    return {name for name in registry if registry.plugin(name).builtin}


@pytest.mark.parametrize("page", HAND, ids=lambda p: str(p.relative_to(ROOT)))
def test_racfs_own_parts_are_named_and_counted_as_the_registries_hold_them(page):
    text = " ".join(page.read_text().split())
    for plural, kind in KINDS.items():
        for listed in re.findall(rf"racf's own {plural} \(((?:`\w+`(?:, )?)+)\)", text):
            assert set(re.findall(r"`(\w+)`", listed)) == _own(kind), (page.name, plural)
        for word in re.findall(rf"racf's own (\w+) {plural}", text):
            if word in WORDS:
                assert WORDS[word] == len(_own(kind)), (page.name, word, plural)


def _commands() -> dict[str, set[str]]:
    from racf.experiments.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    out = {}
    for name, parser in sub.choices.items():
        inner = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        out[name] = set(inner[0].choices) if inner else set()
    return out


def test_every_command_a_page_names_is_the_clis():
    commands = _commands()
    named = set()
    for page in HAND:
        for code in re.findall(r"`([^`\n]+)`", page.read_text()) + re.findall(r"```(?:bash|console|sh)\n(.*?)```",
                                                                             page.read_text(), re.S):
            named |= {(m.group(1), m.group(2), page.name) for m in re.finditer(r"(?<![\w/.-])racf ([a-z][\w-]*)(?: ([a-z][\w-]*))?", code)}
    wrong = sorted((page, f"racf {cmd}") for cmd, _, page in named if cmd not in commands)
    assert wrong == []
    wrong_sub = sorted((page, f"racf {cmd} {sub}") for cmd, sub, page in named
                       if cmd in commands and commands[cmd] and sub and not sub.startswith("-") and sub not in commands[cmd]
                       and cmd != "list")
    assert wrong_sub == []


def test_the_facts_check_sees_a_wrong_count():
    text = "racf's own six metrics"
    word = re.findall(r"racf's own (\w+) metrics", text)[0]
    assert WORDS[word] != len(_own("metric"))


def test_the_link_protocol_the_pages_state_is_the_one_the_code_speaks():
    """The architecture page's table of requests: its version, the distance's range and the requests
    themselves are what racf's wire module checks."""
    from racf.experiments.link import wire

    text = " ".join((ROOT / "docs" / "concepts" / "architecture.md").read_text().split())
    assert f"The protocol (version {wire.PROTOCOL})" in text and f"`pong: true, protocol: {wire.PROTOCOL}`" in text
    lo, hi = wire.DISTANCE_RANGE_M
    assert f"`distance` is a number in [{lo:g}, {hi:g}] m" in text
    table = text.split("| request | fields | answer |", 1)[1].split("An estimate's", 1)[0]
    listed = re.findall(r"\| `(\w+)` \|", table)
    assert set(listed) == set(wire._ANSWERS), listed
