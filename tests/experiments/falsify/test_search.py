"""The searches: deterministic, resumable without redoing an episode, and guided ones find what random search misses."""

import pandas as pd
import pytest

from racf.experiments.falsify.report import best_so_far, first_violation, sampler_summary
from racf.experiments.falsify.search import SearchConfig, episode_seed, run_searches
from racf.experiments.falsify.space import load_space


class FakePool:
    """Stands in for the episode pool: a smooth robustness over the space, no simulator. It counts
    every episode it is asked for, as a pool without a store would run it: nothing here reuses
    an episode, so a search that resumes must not ask again for what its journal holds."""

    def __init__(self):
        self.ran, self.values = 0, []

    def run(self, specs):
        self.ran += len(specs)
        rows = []
        for spec in specs:
            params = spec.attack_params.get("dropout_timed", {})
            # Violations only in a small corner: fast, short run-up, late strike.
            value = 0.3 * (2.0 - spec.speed) + 0.2 * (spec.run_up_m - 1.2) + 0.02 * (8 - params.get("scans", 1)) - 0.05
            rows.append({"robustness_m": value})
            self.values.append(value)
        return pd.DataFrame(rows)


def _space():
    return load_space("odca", ("dropout_timed",))


def test_the_same_search_gives_the_same_trials_and_a_killed_one_resumes_without_rerunning(tmp_path):
    cfg = SearchConfig(_space(), ("tpe", "random"), (0, 1), budget=12, batch=4)
    a, b = FakePool(), FakePool()
    first = run_searches(cfg, tmp_path / "a", a, progress=False)
    again = run_searches(cfg, tmp_path / "b", b, progress=False)
    assert {k: s.trials() for k, s in first.items()} == {k: s.trials() for k, s in again.items()}
    # "Killed" after 8 episodes per search: a longer budget on the same folder goes on from there.
    # TPE starts as random search with the same seed: the two share those episodes (one run each).
    assert [t[1] for t in first[("tpe", 0)].trials()[:8]] == [t[1] for t in first[("random", 0)].trials()[:8]]
    c = FakePool()
    short = SearchConfig(_space(), ("tpe",), (0, 1), budget=8, batch=4)
    run_searches(short, tmp_path / "c", c, progress=False)
    assert c.ran == 2 * 8
    longer = SearchConfig(_space(), ("tpe",), (0, 1), budget=12, batch=4)
    resumed = run_searches(longer, tmp_path / "c", c, progress=False)
    assert c.ran == 2 * 12  # only the 4 new episodes per search ran
    assert {k: s.trials() for k, s in resumed.items()} == {k: first[k].trials() for k in resumed}


def test_trials_asked_but_never_told_are_evaluated_on_resume(tmp_path):
    cfg = SearchConfig(_space(), ("random",), (3,), budget=6, batch=3)
    pool = FakePool()
    searches = run_searches(SearchConfig(_space(), ("random",), (3,), budget=3, batch=3), tmp_path, pool, progress=False)
    search = searches[("random", 3)]
    asked = search.study.ask()  # a kill between ask and tell leaves a RUNNING trial
    _space().suggest(asked)
    resumed = run_searches(cfg, tmp_path, pool, progress=False)[("random", 3)]
    numbers = [n for n, *_ in resumed.trials()]
    assert numbers == sorted(numbers) and asked.number in numbers and len(numbers) == 6


def test_episode_seeds_come_from_the_search_and_the_trial():
    assert episode_seed(0, 7) == 7 and episode_seed(3, 7) == 300_007
    spec = _space().trial_spec({"sign": 3, "speed": 1.5, "run_up_m": 9.0, "stable_steps": 10,
                                "attack.dropout_timed.scans": 2, "attack.dropout_timed.effect": "bias",
                                "attack.dropout_timed.bias_m": 0.5}, episode_seed(1, 2))
    assert spec.seed == 100_002 and spec.run_up_m == pytest.approx(2.36, abs=0.01)  # cut to sign 3's lane
    from racf.experiments.episode.plan import plan_episode

    plan_episode(spec)  # and the lane takes it
    assert spec.attack_params == {"dropout_timed": {"scans": 2, "effect": "bias", "bias_m": 0.5}}


def test_the_report_counts_first_violations_and_censors_seeds_that_found_none():
    assert first_violation([0.3, 0.1, -0.2, -0.5]) == 3 and first_violation([0.1]) is None
    assert list(best_so_far([0.3, 0.5, 0.1], 5)) == [0.3, 0.3, 0.1, 0.1, 0.1]
    s = sampler_summary({0: [0.1, -0.1], 1: [0.2, 0.1], 2: [-0.3]}, budget=2)
    assert s["falsified"] == 2 and s["episodes_to_first_median"] == 2.0 and s["lowest_robustness_m"] == -0.3
    none = sampler_summary({0: [0.1, 0.2], 1: [0.2, 0.1], 2: [-0.3]}, budget=2)
    assert none["episodes_to_first_median"] is None  # under half the seeds found one: beyond the budget


def test_violations_by_value_maps_random_search_draws_only():
    from racf.experiments.falsify.report import violations_by_value

    trials = {("random", 0): [(0, {"sign": 0, "effect": "bias"}, -0.2), (1, {"sign": 1, "effect": "bias"}, 0.3)],
              ("random", 1): [(0, {"sign": 0, "effect": "blackout"}, 0.1)],
              ("tpe", 0): [(0, {"sign": 0, "effect": "bias"}, -0.5)] * 5}  # a guided sampler's draws are biased
    by = violations_by_value(trials, {"sign": [0, 1, 2], "effect": ["blackout", "bias"]})
    assert by["sign"]["0"] == {"n": 2, "violations": 1, "share": 0.5, "share_ci": pytest.approx([0.0945, 0.9055],
                                                                                               abs=1e-3)}
    assert by["sign"]["2"]["n"] == 0 and by["sign"]["2"]["share"] is None
    assert by["effect"]["bias"]["violations"] == 1 and by["effect"]["bias"]["n"] == 2
    assert violations_by_value({("tpe", 0): trials[("tpe", 0)]}, {"sign": [0]}) == {}


def test_the_undetected_objective_steers_the_samplers_but_a_violation_is_still_the_rules(tmp_path):
    from racf.experiments.falsify.search import objective_value

    row = {"robustness_m": 0.2, "undetected_error_m": 0.5}
    assert objective_value(row, "rule") == 0.2 and objective_value(row, "rule-undetected") == pytest.approx(-0.3)
    assert objective_value({"robustness_m": 0.2, "undetected_error_m": None}, "rule-undetected") == 0.2

    class Shaped(FakePool):
        def run(self, specs):
            rows = super().run(specs)
            return rows.assign(undetected_error_m=1.0)  # every value the samplers see is 1 m lower

    cfg = SearchConfig(_space(), ("tpe",), (0,), budget=8, batch=4, objective="rule-undetected")
    pool = Shaped()
    search = run_searches(cfg, tmp_path, pool, progress=False)[("tpe", 0)]
    assert [v for *_, v in search.trials()] == pool.values[:8]  # the rule's, reported
    assert all(t.value == pytest.approx(v - 1.0) for t, (*_, v) in zip(search.study.trials, search.trials()))
    with pytest.raises(ValueError, match="objective must be one of"):
        SearchConfig(_space(), objective="fastest")



def test_the_gap_objective_is_the_clear_gap_and_below_zero_on_contact():
    from racf.experiments.falsify.search import CONTACT_M, objective_value

    assert objective_value({"min_gap_m": 0.31, "no_lead_collision": True}, "gap") == 0.31
    assert objective_value({"min_gap_m": 0.02, "no_lead_collision": False}, "gap") == -CONTACT_M
    assert objective_value({"min_gap_m": -0.01, "no_lead_collision": False}, "gap") == -0.01 - CONTACT_M
    # The rule's objective reads the stop rule's robustness, not the gap.
    assert objective_value({"robustness_m": 0.2, "min_gap_m": 0.5}, "rule") == 0.2


def test_the_guarantee_spaces_search_the_supervisor_within_and_beyond_delta():
    from pathlib import Path

    import racf.experiments.falsify as falsify

    folder = Path(falsify.__file__).parent / "spaces"
    inside = load_space("odca", ("lead_range_error",), folder / "guarantee.toml")
    outside = load_space("odca", ("lead_range_error",), folder / "guarantee-outside.toml")
    from racf.experiments.car.supervisor.envelope import Envelope

    # Inside: the attacker's share of delta (0.05 m, the rest is the witnesses' own error); outside: 0.2 m.
    assert Envelope().attack_error_m == 0.05
    for space, share in ((inside, 0.05), (outside, 0.2)):
        dims = {d.name: d for d in space.dimensions}
        bias, amp = dims["attack.lead_range_error.bias_m"], dims["attack.lead_range_error.amp_m"]
        assert max(abs(bias.low), abs(bias.high)) + amp.high == pytest.approx(share)
        assert dims["scenario.lead_vehicle.decel"].high == 6.0 and dims["scenario.lead_vehicle.gap_m"].low >= 0.66
        spec = space.extremes()[0]
        assert spec.supervisor and spec.target == "lead_vehicle" and spec.t_atk == (30.0, 30.0)
    sign = load_space("odca", ("patch_occlusion",), folder / "guarantee-sign.toml")
    assert all(spec.supervisor and spec.target == "sign" for spec in sign.extremes())
