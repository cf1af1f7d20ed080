"""The CLI's choices, its help and the README's tables come from the attack and estimator registries."""

from pathlib import Path

import pytest

from racf.experiments.cli import main
from racf.experiments.cli.common import registry_markdown
from racf.experiments.episode.estimators import ESTIMATORS
from racf.sim.attacks import ATTACKS

ROOT = Path(__file__).resolve().parents[3]


def test_help_names_every_registered_attack_and_estimator(capsys):
    for command in ("trials", "sweep"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        out = capsys.readouterr().out
        flat = " ".join(out.split())
        for name in (*ATTACKS, *ESTIMATORS):
            assert name in flat, (command, name)


def test_list_prints_the_registries(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in (*ATTACKS, *ESTIMATORS))


def test_the_readme_tables_are_the_registries():
    # Regenerate with `racf list --markdown` when an attack or estimator is added.
    assert registry_markdown() in (ROOT / "README.md").read_text()
