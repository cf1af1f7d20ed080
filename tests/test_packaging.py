"""racf installs as one namespace that carries its assets: setuptools' package-dir maps the design
card's folders (no committed links), the package list names every package folder, nothing imports
the old top-level names, the development install exposes racf alone, and (slow) a wheel works in a
fresh venv."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import racf
from racf.assets import asset_path

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
TOPS = {"racf": "core", "racf.assets": "assets", "racf.sim": "sim", "racf.odca": "odca",
        "racf.controllers": "controllers", "racf.experiments": "experiments"}


def test_every_package_folder_installs_under_racf_and_nothing_else():
    setuptools = PYPROJECT["tool"]["setuptools"]
    # The one folder mapping: setuptools' package-dir, each package to its design card folder.
    assert setuptools["package-dir"] == TOPS
    found = {"racf", "racf.assets"}
    for name, folder in TOPS.items():
        if name in ("racf", "racf.assets"):
            continue
        for init in (ROOT / folder).rglob("__init__.py"):
            found.add(".".join([name, *init.parent.relative_to(ROOT / folder).parts]))
    data_only = {name for name in setuptools["package-data"] if name not in found}  # folders of data, no code
    assert all(not (ROOT / TOPS[".".join(name.split(".")[:2])] / Path(*name.split(".")[2:]) / "__init__.py").exists()
               for name in data_only)
    assert set(setuptools["packages"]) == found | data_only
    assert all(p == "racf" or p.startswith("racf.") for p in setuptools["packages"])


def test_the_checkout_commits_no_links():
    """A link is a 6-byte text file in a Windows checkout: the mapping lives in pyproject.toml instead."""
    listed = subprocess.run(["git", "ls-files", "-s"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    assert [line.split("\t")[1] for line in listed.splitlines() if line.startswith("120000")] == []


def test_the_development_install_exposes_racf_alone(tmp_path):
    """From outside the checkout, the design card's folders are no top-level packages; racf maps them."""
    ask = ("import importlib.util, json; print(json.dumps({n: importlib.util.find_spec(n) is not None for n in "
           "('sim', 'odca', 'controllers', 'experiments', 'core', 'racf.sim', 'racf.odca.online', 'racf.plugins')}))")
    done = subprocess.run([sys.executable, "-c", ask], cwd=tmp_path, capture_output=True, text=True, check=True,
                          env={**os.environ, "PYTHONPATH": ""})
    found = json.loads(done.stdout)
    assert found == {"sim": False, "odca": False, "controllers": False, "experiments": False, "core": False,
                     "racf.sim": True, "racf.odca.online": True, "racf.plugins": True}


def test_no_module_imports_the_old_top_level_names():
    old = re.compile(r"^\s*(from|import) (sim|odca|controllers|experiments|core)\b", re.M)
    offenders = [str(path.relative_to(ROOT)) for folder in ("sim", "odca", "controllers", "experiments", "core",
                                                            "tests", "examples")
                 for path in (ROOT / folder).rglob("*.py") if old.search(path.read_text())]
    assert offenders == []


@pytest.mark.slow  # 4-5 s: the default run keeps under two minutes on 2 cores
def test_assets_are_found_through_the_package_not_the_checkout():
    assert asset_path("qcar2_map", "qcar2.xml").is_file()
    assert (asset_path("checkpoints", "odca-head") / "odca.json").is_file()
    with pytest.raises(FileNotFoundError, match="racf asset 'nowhere'"):
        asset_path("nowhere")
    reach = re.compile(r"parents\[\d\]\s*/\s*\"assets\"")
    assert not [p for p in ROOT.glob("*/**/*.py") if ".venv" not in p.parts and reach.search(p.read_text())]


def test_the_version_is_the_distributions(capsys):
    from racf.experiments.cli import main

    assert main(["--version"]) == 0 and capsys.readouterr().out.strip() == f"racf {racf.__version__}"
    assert racf.__version__ == PYPROJECT["project"]["version"]


@pytest.mark.slow
def test_the_wheel_installs_and_runs_in_a_fresh_venv_outside_the_repository(tmp_path):
    """Builds the wheel, installs it (torch's CPU wheel first) in a new venv, and from a folder
    outside the checkout: racf --version, the imports, no generic top-level package, the demo."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"), "PYTHONPATH": ""}
    run = lambda *cmd, **kw: subprocess.run(cmd, check=True, capture_output=True, text=True, env=env, **kw)  # noqa: E731
    run(sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation", str(ROOT), "-w",
        str(tmp_path / "wheel"))
    (wheel,) = (tmp_path / "wheel").glob("racf-*.whl")
    run(sys.executable, "-m", "venv", str(tmp_path / "venv"))
    py, bin_ = tmp_path / "venv" / "bin" / "python", tmp_path / "venv" / "bin"
    run(str(py), "-m", "pip", "install", "-q", "torch==2.13.0")
    run(str(py), "-m", "pip", "install", "-q", str(wheel))
    outside = tmp_path / "elsewhere"
    (outside / "experiments").mkdir(parents=True)  # a user's own folder of that name shadows nothing
    assert run(str(bin_ / "racf"), "--version", cwd=outside).stdout.strip() == f"racf {racf.__version__}"
    run(str(py), "-c", "import racf.sim, racf.odca, racf.experiments.episode", cwd=outside)
    site = next((tmp_path / "venv" / "lib").glob("python3*/site-packages"))
    assert not {"sim", "odca", "controllers", "experiments"} & {p.name for p in site.iterdir()}
    demo = run(str(bin_ / "racf"), "demo", "--out", str(outside / "demo"), cwd=outside).stdout
    assert "attack+odca" in demo and (outside / "demo").is_dir()


def test_no_module_of_racfs_packages_is_over_400_lines():
    """Small modules, one job each: a file that grows past 400 lines is split along its seams."""
    long = {str(p.relative_to(ROOT)): n for folder in set(TOPS.values()) for p in (ROOT / folder).rglob("*.py")
            if (n := len(p.read_text().splitlines())) > 400}
    assert long == {}


def test_each_lazy_package_names_the_same_imports_for_editors_as_its_stub():
    """A package that loads its names on first use (lazy_loader, from its ``__init__.pyi``) lists the same
    imports under TYPE_CHECKING in its ``__init__.py``, for editors that read no stub."""
    import ast

    stubs = sorted(ROOT.glob("*/__init__.pyi")) + sorted(ROOT.glob("*/*/__init__.pyi"))
    assert len(stubs) >= 6
    for stub in stubs:
        def imports(tree):
            return sorted((node.module, tuple(a.name for a in node.names)) for node in ast.walk(tree)
                          if isinstance(node, ast.ImportFrom) and node.level == 1)
        init = stub.with_suffix(".py")
        assert imports(ast.parse(stub.read_text())) == imports(ast.parse(init.read_text())), init
