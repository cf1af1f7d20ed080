"""The tutorial's topic table is the one racf writes (it cannot go stale)."""

from __future__ import annotations

import re
from pathlib import Path

from racf.experiments.bags.topics import QUANSER_TOPICS, RACF_TOPICS

PAGE = Path(__file__).resolve().parents[3] / "docs" / "tutorials" / "ros2-bags.md"


def test_the_tutorials_topic_table_names_each_topic_as_racf_writes_it():
    rows = {}
    for line in PAGE.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[0].startswith("`/"):
            for name in re.findall(r"`(/[^`]+)`", cells[0]):
                rows[name] = (cells[1].strip("`"), cells[2].strip("`"))
    for topic in (*QUANSER_TOPICS.values(), *RACF_TOPICS.values()):
        assert topic.name in rows, topic.name
        assert rows[topic.name] == (topic.msgtype, topic.frame), topic.name
