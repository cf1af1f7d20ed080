"""Counterexamples: saved with the full episode spec, replayed to the bit, and the shipped suite replays."""

import json
from dataclasses import replace

import pytest

from racf.experiments.episode import TrialSpec
from racf.experiments.falsify.cases import (RESEED_STRIDE, SUITE, Case, distinct, load_case, replay_case, reseed_case,
                                           save_case, spec_from_json)
from racf.experiments.sweeps.executors import run_episode


def test_a_saved_case_replays_to_the_same_robustness_to_the_bit(tmp_path):
    spec = TrialSpec("attack", sign=1, speed=1.8, seed=11, rho=(0.95, 0.95), t_atk=(2.5, 2.5), run_up_m=1.6,
                     stable_steps=4)
    row = run_episode(spec, str(tmp_path / "episodes"))  # as a search's worker runs it
    path = save_case(tmp_path / "cases", spec, row, {"sampler": "random", "seed": 0, "trial": 0})
    case = load_case(path)
    assert case.spec == spec and case.robustness_m == row["robustness_m"]
    replay = replay_case(case)
    assert replay.same_code and replay.identical and replay.robustness_m == row["robustness_m"]
    other = replay_case(case, defence="odca")  # the same scenario and attack against another defence
    assert other.spec.setting == "attack+odca" and other.identical is None



def test_reseeding_runs_the_same_parameters_under_other_noise_seeds(monkeypatch):
    spec = TrialSpec("clean+dropout_timed+odca", sign=1, speed=1.4, seed=59, run_up_m=1.5, stable_steps=45)
    case = Case(spec, -1.1, "confirmed_lost", "code", {}, "a-case")
    ran = []

    class _Result:
        def __init__(self, s):
            self.robustness_m = -0.5 if s.seed % 2 else 0.3

    def fake_trial(s):
        ran.append(s)
        return _Result(s), None

    monkeypatch.setattr("racf.experiments.episode.run_trial", fake_trial)
    values = reseed_case(case, 3)
    assert values == [-0.5 if (59 + RESEED_STRIDE * k) % 2 else 0.3 for k in (1, 2, 3)]
    assert [s.seed for s in ran] == [59 + RESEED_STRIDE * k for k in (1, 2, 3)]
    assert all(s == replace(spec, seed=s.seed) for s in ran)  # only the noise seed changes
    reseed_case(case, 1, defence="ekf")
    assert ran[-1].setting == "clean+dropout_timed+ekf" and ran[-1].seed == 59 + RESEED_STRIDE
    with pytest.raises(ValueError, match="integer in"):
        reseed_case(case, 0)


def test_reseeding_a_real_case_is_deterministic():
    spec = TrialSpec("attack", sign=2, speed=1.5, seed=3, rho=(0.95, 0.95), t_atk=(2.5, 2.5), run_up_m=1.6)
    case = Case(spec, -1.0, None, "code", {}, "a-case")
    first = reseed_case(case, 1)
    assert len(first) == 1 and first == reseed_case(case, 1)

def test_specs_round_trip_through_json_and_bad_files_are_clear_errors(tmp_path):
    spec = TrialSpec("clean+dropout_timed+odca", sign=3, speed=1.2, seed=4, run_up_m=2.0,
                     attack_params={"dropout_timed": {"scans": 2, "effect": "bias", "bias_m": 0.4}})
    from dataclasses import asdict

    assert spec_from_json(json.loads(json.dumps(asdict(spec)))) == spec
    bad = tmp_path / "bad.json"
    bad.write_text("{\"version\": 1}")
    with pytest.raises(ValueError, match="not a racf case file"):
        load_case(bad)
    with pytest.raises(ValueError, match="cannot read"):
        load_case(tmp_path / "missing.json")


def test_distinct_keeps_the_lowest_per_setting_sign_and_failure():
    rows = [{"setting": "attack", "sign": 1, "failure": "braked_late", "robustness_m": -0.1},
            {"setting": "attack", "sign": 1, "failure": "braked_late", "robustness_m": -0.4},
            {"setting": "attack", "sign": 2, "failure": "braked_late", "robustness_m": -0.2}]
    kept = distinct(rows)
    assert [r["robustness_m"] for r in kept] == [-0.4, -0.2]


def test_the_shipped_suite_is_well_formed():
    files = sorted(SUITE.glob("*.json"))
    assert files, "the regression suite holds the distinct failures found for the built-in defences"
    for f in files:
        case = load_case(f)
        assert case.robustness_m < 0 and case.spec.trial_id


@pytest.mark.slow
@pytest.mark.parametrize("path", sorted(SUITE.glob("*.json")), ids=lambda p: p.stem)
def test_each_shipped_case_replays(path):
    """On the code it was found on, to the bit; on other code, it runs and says whether it survives."""
    case = load_case(path)
    replay = replay_case(case)
    assert replay.identical in (True, None)
    if replay.same_code:
        assert replay.robustness_m == case.robustness_m and not replay.survived
