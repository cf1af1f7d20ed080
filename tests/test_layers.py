"""The house's floors, as import-linter contracts (``[tool.importlinter]`` in pyproject.toml): racf's
floor stands on nothing of racf's, the simulator, ODCA and the car's software never import the
experiments or each other, the experiments' floors and the simulator's only import downwards, and no
two packages import each other at any depth. grimp reads every import, relative ones and those inside
functions, so a new one that breaks a rule fails here; the checks below show that it would."""

from __future__ import annotations

import ast
import textwrap
from pathlib import Path

import pytest
from importlinter.cli import lint_imports

ROOT = Path(__file__).resolve().parents[1]


def test_every_contract_is_kept():
    assert lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True) == 0


def test_racfs_floor_names_no_upper_floor_even_in_a_string():
    """The registries recognise a part by its base class's ``racf_part``, not by an upper floor's module
    path given as a string (a message may tell a user which class to subclass)."""
    upper = ("racf.sim", "racf.experiments", "racf.controllers", "racf.odca")
    named = []
    for path in (ROOT / "core").glob("*.py"):
        tree = ast.parse(path.read_text())
        docs = {id(n.body[0].value) for n in ast.walk(tree) if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef))
                and n.body and isinstance(n.body[0], ast.Expr)}
        named += [(path.name, node.value) for node in ast.walk(tree) if isinstance(node, ast.Constant)
                  and isinstance(node.value, str) and id(node) not in docs and " " not in node.value
                  and node.value.startswith(upper)]
    assert named == []


def _house(tmp_path: Path, root: str, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = tmp_path / root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    config = tmp_path / f"{root}.ini"
    config.write_text(textwrap.dedent(f"""
        [importlinter]
        root_package = {root}

        [importlinter:contract:floors]
        name = floors
        type = layers
        containers = {root}
        layers =
            surface
            engine

        [importlinter:contract:cycles]
        name = cycles
        type = acyclic_siblings
        ancestors = {root}
        """))
    return config


@pytest.mark.parametrize("files", [
    # An engine module that reaches up a floor with a relative import.
    {"engine/run.py": "from ..surface import page\n", "surface/page.py": "from ..engine import run\n"},
    # Two engine packages importing each other, relatively, inside a function.
    {"engine/a/x.py": "def f():\n    from ..b import y\n", "engine/b/y.py": "from ..a import x\n"},
])
def test_the_contracts_see_relative_imports_up_a_floor_and_in_cycles(tmp_path, monkeypatch, files):
    skeleton = {"__init__.py": "", "engine/__init__.py": "", "surface/__init__.py": "", "surface/page.py": "",
                "engine/a/__init__.py": "", "engine/b/__init__.py": ""}
    monkeypatch.syspath_prepend(str(tmp_path))
    broken = _house(tmp_path, f"broken_{tmp_path.name}", {**skeleton, **files})
    clean = _house(tmp_path, f"clean_{tmp_path.name}", skeleton)
    assert lint_imports(config_filename=str(broken), no_cache=True) == 1
    assert lint_imports(config_filename=str(clean), no_cache=True) == 0
