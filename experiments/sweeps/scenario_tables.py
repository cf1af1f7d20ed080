"""A scenario's own table in a sweep spec (``Scenario.table``, a table named after it): its
parameters, a value or a list of values each, whose ``control`` values (no other car, say) stand for the
plain approach of the scenario's target kind, so one spec runs each episode without and with it."""

from __future__ import annotations

import itertools

from racf.plugins import SCENARIOS

__all__ = ["scenario_tables", "check_tables", "table_combos", "situations"]


def scenario_tables() -> dict[str, str]:
    """The top-level tables scenarios take in a spec, table -> scenario."""
    return {SCENARIOS[name].table: name for name in SCENARIOS if SCENARIOS[name].table}


def check_tables(tables: dict, target: str) -> None:
    """ValueError names a table no scenario takes, a field its scenario lacks, a value out of its range
    (a ``control`` value is allowed beside it) or a table a spec of ``target`` cannot take."""
    if not isinstance(tables, dict):
        raise ValueError("tables must map a scenario's table name to its table")
    known = scenario_tables()
    for table, content in tables.items():
        if table not in known:
            raise ValueError(f"unknown table [{table}]; scenarios' tables: {sorted(known)}")
        scenario = SCENARIOS[known[table]]
        if not isinstance(content, dict):
            raise ValueError(f"{table} must be a table ([{table}] with {[p.name for p in scenario.params]})")
        unknown = sorted(set(content) - {p.name for p in scenario.params})
        if unknown:
            raise ValueError(f"unknown field(s) {unknown} in [{table}]; allowed: "
                             f"{sorted(p.name for p in scenario.params)}")
        for name, values in content.items():
            listed = values if isinstance(values, list) else [values]
            if not listed:
                raise ValueError(f"{table}.{name} must be a value or a non-empty list of values, got {values!r}")
            for value in listed:
                if scenario.control.get(name, object()) != value:
                    scenario.param(name).check(value, scenario.name)
        if target not in (scenario.name, scenario.target) and any(table_combos(tables, table)):
            raise ValueError(f"[{table}] lists the parameters of scenario {scenario.name!r} (a {scenario.target} "
                             f"approach); target {target!r} cannot take it")


def table_combos(tables: dict, table: str) -> list[dict]:
    """Every combination of a scenario's table's values; {} for the control (the plain approach)."""
    scenario = SCENARIOS[scenario_tables()[table]]
    content = {k: v if isinstance(v, list) else [v] for k, v in tables[table].items()}
    combos = [dict(zip(content, combo)) for combo in itertools.product(*content.values())]
    return [{} if any(scenario.control.get(k, object()) == v for k, v in combo.items()) else combo
            for combo in combos]


def situations(target: str, combos: list[dict], tables: dict) -> list[tuple[str, dict]]:
    """(scenario, its parameters) of every episode of a cell: ``target`` with each of its own
    ``[scenario.<target>]`` ``combos``, crossed with the scenario tables' combinations (whose control
    runs ``target``)."""
    out: list[tuple[str, dict]] = [(target, situation) for situation in combos]
    for table in tables:
        name = scenario_tables()[table]
        out = [(name, combo | situation) if combo else (plain, situation)
               for combo in table_combos(tables, table) for plain, situation in out]
    return out
