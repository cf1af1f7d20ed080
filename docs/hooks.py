"""mkdocs hooks: the reference pages are written from the code before every build (at config time).

The API reference reads the package as it installs: mkdocstrings finds ``racf`` on the path, where
the development install's tree of links (pyproject's package-dir: ``racf`` = ``core/``,
``racf.sim`` = ``sim/``, ...) puts it."""

from __future__ import annotations

from pathlib import Path

from mkdocs.plugins import event_priority


@event_priority(100)  # before mkdocstrings reads its search paths
def on_config(config, **kwargs):
    from racf.experiments.cli.reference import write_pages, write_readme

    root = Path(config["config_file_path"]).resolve().parent
    write_pages(Path(config["docs_dir"]))
    write_readme(root / "README.md")
    return config
