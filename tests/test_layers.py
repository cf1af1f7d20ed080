"""The house's floors: racf's floor (``racf/``) stands on nothing of racf's, the simulator and the
car's software never import the experiments, and no two packages of ``experiments/`` import each
other (each import is read from the source, so a new one that breaks a rule fails here)."""

import ast
from pathlib import Path

import networkx as nx

ROOT = Path(__file__).resolve().parents[1]
#: Each installed package and its folder in the repository.
FOLDERS = {"racf": "racf", "racf.sim": "sim", "racf.controllers": "controllers", "racf.odca": "odca",
           "racf.experiments": "experiments"}


def _module(path: Path) -> str:
    rel = path.relative_to(ROOT)
    package = next(name for name, folder in FOLDERS.items() if rel.parts[0] == folder)
    parts = list(rel.with_suffix("").parts[1:])
    return ".".join([package, *(parts[:-1] if parts[-1] == "__init__" else parts)])


def imports() -> dict[str, set[str]]:
    """Module -> the racf modules it imports (at the top or inside functions)."""
    found: dict[str, set[str]] = {}
    for folder in FOLDERS.values():
        for path in (ROOT / folder).rglob("*.py"):
            names = set()
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names.add(node.module)
                elif isinstance(node, ast.Import):
                    names.update(alias.name for alias in node.names)
            found[_module(path)] = {n for n in names if n == "racf" or n.startswith("racf.")}
    return found


def _floor(module: str) -> str:
    """The package a module stands in: ``racf`` (the floor), ``racf.sim``, ... ``racf.experiments``."""
    return max((p for p in FOLDERS if module == p or module.startswith(p + ".")), key=len)


def test_the_floor_imports_nothing_above_it():
    above = {m: sorted(i for i in deps if _floor(i) != "racf") for m, deps in imports().items() if _floor(m) == "racf"}
    assert not {m: deps for m, deps in above.items() if deps}


def test_the_simulator_and_the_car_never_import_the_experiments():
    wrong = {m: sorted(i for i in deps if _floor(i) == "racf.experiments")
             for m, deps in imports().items() if _floor(m) in ("racf.sim", "racf.controllers", "racf.odca")}
    assert not {m: deps for m, deps in wrong.items() if deps}


def _package_graph(edges: dict[str, set[str]]) -> nx.DiGraph:
    graph = nx.DiGraph()
    for module, deps in edges.items():
        for dep in deps:
            a, b = module.split(".")[:3], dep.split(".")[:3]
            if a[:2] == b[:2] == ["racf", "experiments"] and len(a) == len(b) == 3 and a != b:
                graph.add_edge(".".join(a), ".".join(b))
    return graph


def test_no_two_packages_of_the_experiments_import_each_other():
    cycles = list(nx.simple_cycles(_package_graph(imports())))
    assert cycles == [], f"package cycles: {cycles}"


def test_the_cycle_check_sees_a_cycle():
    edges = {"racf.experiments.a.x": {"racf.experiments.b.y"}, "racf.experiments.b.y": {"racf.experiments.a.z"}}
    assert list(nx.simple_cycles(_package_graph(edges)))
