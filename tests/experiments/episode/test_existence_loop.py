"""The existence vote in the closed loop, against what detector-only does (slow: a few episodes)."""

import pytest

from racf.experiments.episode import TrialSpec, run_trial

pytestmark = pytest.mark.slow


def _run(setting, case, sign=0, **kwargs):
    result, _ = run_trial(TrialSpec(setting, sign, 1.5, 3, target="stale_map", scenario_params={"case": case},
                                    **kwargs), clean_pass=False)
    return result


def test_a_phantom_stops_detector_only_and_not_the_vote():
    assert _run("clean+odca", "phantom").needless_stop is True
    assert _run("clean+vote", "phantom").needless_stop is False


def test_a_sticker_from_the_start_on_a_mapped_sign_runs_detector_only_and_not_the_vote():
    sticker = {"physical_patch": {"texture": "learned-approach", "size": 0.6, "from_start": True}}
    # At sign 1 (racf-5: detector-only stops at none of its 15 sticker episodes, the vote at 14).
    assert not _run("clean+physical_patch+odca", "mapped", sign=1, attack_params=sticker).success
    assert _run("clean+physical_patch+vote", "mapped", sign=1, attack_params=sticker).success


def test_a_removed_sign_stops_map_only_and_not_the_vote():
    assert _run("clean+map_only", "removed").needless_stop is True
    assert _run("clean+vote", "removed").needless_stop is False


def test_the_frustum_attack_on_a_mapped_sign_is_caught_moving_and_the_vote_stops():
    # racf-5's white box on the vote: the sticker, and the sign's depth and LiDAR returns moved away at 3 m/s
    # (its episode 36: sign 0 at 1.68 m/s; the vote stopped at 1 of racf-5's 60 before the check, 54 with it).
    spoof = {"physical_patch": {"texture": "learned-approach", "size": 0.6, "from_start": True},
             "frustum_spoof": {"trigger": "always", "rate_mps": 3.0}}
    result, log = run_trial(TrialSpec("attack+frustum_spoof+physical_patch+vote", 0, 1.68, 36, target="stale_map",
                                      scenario_params={"case": "mapped"}, attack_params=spoof, t_atk=(60.0, 60.0)),
                            clean_pass=False)
    assert result.success and log["wit_moving"].max() == 1.0
