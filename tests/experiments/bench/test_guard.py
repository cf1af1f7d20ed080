"""The speed guard's verdict: a ratio more than 15 % above the stored one fails, one within passes
(the timing itself is a benchmark, run by `make check-speed`, not here)."""

from __future__ import annotations

import json

import pytest

from racf.experiments.bench import guard, guard_store
from racf.experiments.bench.guard import GuardResult
from tests.conftest import run_cli


@pytest.fixture
def stored(tmp_path, monkeypatch):
    path = tmp_path / "speed-guard.json"
    path.write_text(json.dumps({"history": [{"commit": "abc1234", "ratio": 15.0}]}))
    monkeypatch.setattr(guard_store, "GUARD_FILE", path)
    monkeypatch.setattr(guard_store.load_guard, "__defaults__", (path,))
    return path


@pytest.mark.parametrize("ratio, code", [(16.5, 0), (17.4, 1), (12.0, 0)])
def test_check_fails_only_past_the_tolerance(stored, monkeypatch, ratio, code):
    monkeypatch.setattr(guard, "measure_guard",
                        lambda rounds, slowdown: GuardResult([5.0], [5.0 / ratio], [ratio], 100, slowdown))
    got, out = run_cli(["bench", "guard", "--check", "--json"])
    result = json.loads(out)
    assert got == code and result["passed"] == (code == 0)
    assert result["change"] == pytest.approx(ratio / 15.0 - 1.0)


def test_check_without_a_stored_ratio_says_how_to_make_one(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(guard_store.load_guard, "__defaults__", (tmp_path / "none.json",))
    code, _ = run_cli(["bench", "guard", "--check"])
    assert code == 2 and "racf bench guard --store" in capsys.readouterr().err
