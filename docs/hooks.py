"""mkdocs hooks: the reference pages are written from the code before every build (at config time), and the API
reference reads the package as it installs (one ``racf`` namespace over the top-level folders).

The sources stay where the design card puts them (``sim/``, ``odca/``, ...); setuptools maps them
under ``racf``. mkdocstrings reads sources statically, so the build lays out that namespace in
``build/api-src/racf`` (racf's own files copied, the folders linked) (mkdocs.yml points the handler there)."""

from __future__ import annotations

import shutil
from pathlib import Path

from mkdocs.plugins import event_priority

_FOLDERS = {"sim": "sim", "odca": "odca", "controllers": "controllers", "experiments": "experiments",
            "assets": "assets"}


@event_priority(100)  # before mkdocstrings reads its search paths, which must exist by then
def on_config(config, **kwargs):
    from racf.experiments.cli.reference import write_pages, write_readme

    root = Path(config["config_file_path"]).resolve().parent
    write_pages(Path(config["docs_dir"]))
    write_readme(root / "README.md")
    view = root / "build" / "api-src" / "racf"
    shutil.rmtree(view, ignore_errors=True)
    view.mkdir(parents=True)
    for path in (root / "racf").iterdir():  # copies: a linked __init__ would be read from where it lies
        if path.is_file():
            shutil.copy2(path, view / path.name)
    for name, folder in _FOLDERS.items():
        (view / name).symlink_to(root / folder, target_is_directory=True)
    return config
