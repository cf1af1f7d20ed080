"""A scenario's plan is pure: planning the same spec twice gives the same plan, and a plan leaves the
route's draft it was given as it was (a scenario that edits the map's cached records in place would
move the next episode's sign)."""

from __future__ import annotations

import copy

import pytest

from racf.experiments.episode import TrialSpec
from racf.experiments.episode.plan import plan_episode
from racf.plugins import SCENARIOS

CASES = [("sign", {}), ("obstacle", {}), ("cross_traffic", {"cars": 2, "gap_s": 1.0}),
         ("stale_map", {"case": "moved", "shift_m": 1.2}), ("stale_map", {"case": "phantom"})]


def _facts(plan) -> tuple:
    return (repr(plan.reset_options), [(t.stop_s, t.target_s, t.mapped, tuple(t.target.position))
                                       for t in plan.mission.targets], plan.start_s_m)


@pytest.mark.parametrize("target, params", CASES)
def test_planning_twice_gives_the_same_plan_and_leaves_the_draft_alone(target, params, monkeypatch):
    spec = TrialSpec("clean", 0 if target == "obstacle" else 2, 1.0, 0, target=target, scenario_params=params)
    drafts = []
    planned = SCENARIOS[target].plan

    def keep(self, spec, values, draft):
        drafts.append((draft, copy.deepcopy(_facts(draft))))
        return planned(self, spec, values, draft)

    monkeypatch.setattr(SCENARIOS[target], "plan", keep)
    first, second = plan_episode(spec), plan_episode(spec)
    assert _facts(first) == _facts(second)
    for draft, before in drafts:
        assert _facts(draft) == before
