"""mkdocs hooks: the reference pages are written from the code before every build (at config time).

The API reference reads the package as it installs: mkdocstrings finds ``racf`` on the path, where
the development install's tree of links (pyproject's package-dir: ``racf`` = ``core/``,
``racf.sim`` = ``sim/``, ...) puts it."""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.plugins import event_priority


@event_priority(100)  # before mkdocstrings reads its search paths
def on_config(config, **kwargs):
    from racf.experiments.cli.reference import write_pages, write_readme

    root = Path(config["config_file_path"]).resolve().parent
    write_pages(Path(config["docs_dir"]))
    write_readme(root / "README.md")
    return config


#: A link of the boards' HTML to a card's page: Markdown, so that it works on GitHub too.
_CARD_LINK = re.compile(r'href="(cards/[^"#]+)\.md"')


def on_page_content(html, page, config, files):
    """The boards' links to card pages, written as ``.md`` (GitHub follows them), point at the built
    ``.html`` pages: mkdocs rewrites Markdown's links, not those inside raw HTML."""
    return _CARD_LINK.sub(r'href="\1.html"', html)
