"""The command line by group: each grouped command is its flat one (same flags, same handler) under
a short name, the flat names still work but are not listed, and ``racf bench FLAGS`` is still the
offline benchmark."""

import argparse

import pytest

from racf.experiments.cli import build_parser, main
from racf.experiments.cli.groups import GROUPS, canonical_argv


def _sub(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))


def _options(parser: argparse.ArgumentParser) -> set[str]:
    return {o for a in parser._actions for o in a.option_strings}


def test_each_grouped_command_has_its_flat_commands_flags_and_handler():
    top = _sub(build_parser())
    for group, (_, commands) in GROUPS.items():
        inner = _sub(top.choices[group])
        assert set(inner.choices) == set(commands)
        for short, flat in commands.items():
            grouped, old = inner.choices[short], top.choices[flat]
            assert _options(grouped) == _options(old)
            assert grouped.get_default("handler") is old.get_default("handler")


def test_the_help_lists_the_groups_not_the_flat_names(capsys):
    assert main(["--help"]) == 0
    listed = capsys.readouterr().out
    assert all(f"\n    {group} " in listed for group in GROUPS)
    assert "bench-sim" not in listed and "train-detector" not in listed and "pretrain-prior" not in listed


@pytest.mark.parametrize("old, new", [(["evaluate"], ["odca", "evaluate"]), (["train"], ["odca", "train"])])
def test_a_flat_name_and_its_group_name_do_the_same(tmp_path, capsys, old, new):
    missing = ["--dataset", str(tmp_path / "none")]
    assert main(old + missing) == main(new + missing) == 2
    first, second = capsys.readouterr().err.strip().splitlines()
    assert first.split(":", 1)[1] == second.split(":", 1)[1] and second.startswith(f"racf {' '.join(new)}:")


def test_bench_with_the_offline_benchmarks_flags_is_that_benchmark():
    assert canonical_argv(["bench", "--quick"]) == ["bench-offline", "--quick"]
    assert canonical_argv(["bench"]) == ["bench-offline"]
    assert canonical_argv(["bench", "sim", "--json"]) == ["bench", "sim", "--json"]
    assert canonical_argv(["bench", "--help"]) == ["bench", "--help"]
    assert canonical_argv(["trials", "-n", "2"]) == ["trials", "-n", "2"]
