"""The reading chain: a track with no break is vouched, a jump no car makes is refused for as long as
it goes on, and what appears from nowhere waits for two range witnesses."""

import math

import pytest

from racf.experiments.car.supervisor.envelope import Envelope
from racf.experiments.car.supervisor.track import CarriedTarget
from racf.experiments.car.supervisor.vouch import ChainConfig, ReadingChain, agree_m

NAN = math.nan
DT = 0.02


def _carried(distance: float) -> CarriedTarget:
    carried = CarriedTarget(Envelope())
    carried.vouch(distance, 0.0, lead_known=True)
    return carried


def test_a_first_sight_on_a_lane_not_yet_watched_is_vouched_and_the_nearest_witness_read():
    chain = ReadingChain()
    verdict = chain.step((1.0, 0.9, NAN), 0.0, DT, CarriedTarget(Envelope()))
    assert verdict.vouched and verdict.reading_m == 0.9


def test_a_jump_away_from_the_carried_target_is_refused_while_it_goes_on():
    chain, carried = ReadingChain(), _carried(1.0)
    assert chain.step((1.0, NAN, NAN), 0.0, DT, carried).vouched
    for _ in range(100):  # 2 s of a frustum spoof: both range witnesses 1 m farther, smoothly on
        verdict = chain.step((2.0, 2.0, NAN), 0.0, DT, carried)
        carried.predict(0.0, DT)
        assert verdict.refused and not verdict.vouched
    # Even once the carried bounds have grown past it: the chain was born a jump.
    assert carried.holds(2.0, agree_m(2.0))


def test_a_phantom_nearer_than_the_target_can_be_is_implausible_until_two_witnesses_agree():
    config = ChainConfig(confirm_frames=3)
    chain, carried = ReadingChain(config), _carried(1.0)
    chain.step((1.0, 1.0, NAN), 0.0, DT, carried)
    # The picture's depth reads 0.5 m, the LiDAR sees nothing there: implausible, however long.
    for _ in range(10):
        verdict = chain.step((0.5, NAN, NAN), 0.0, DT, carried)
        assert verdict.implausible and not verdict.vouched
    # A real car that cut in: the depth and the LiDAR agree on it, 3 frames on end.
    verdicts = [chain.step((0.5, 0.48, NAN), 0.0, DT, carried) for _ in range(3)]
    assert [v.vouched for v in verdicts] == [False, False, True]


def test_on_a_watched_lane_a_car_first_seen_too_near_came_from_nowhere():
    chain = ReadingChain(ChainConfig(watch_s=1.0, seen_from_m=1.5))
    nothing = CarriedTarget(Envelope())
    for _ in range(60):
        chain.step((NAN, NAN, NAN), 0.0, DT, nothing)
    assert chain.step((0.8, NAN, NAN), 0.0, DT, nothing).implausible
    far = ReadingChain(ChainConfig(watch_s=1.0, seen_from_m=1.5))
    for _ in range(60):
        far.step((NAN, NAN, NAN), 0.0, DT, nothing)
    assert far.step((2.0, NAN, NAN), 0.0, DT, nothing).vouched


def test_a_chain_follows_the_relative_motion_and_a_gap_ends_it():
    chain, carried = ReadingChain(ChainConfig(gap_s=0.5)), _carried(1.0)
    chain.step((1.0, NAN, NAN), 0.0, DT, carried)
    # Closing at 1 m/s for 0.2 s: 0.8 m is where the chain expects it.
    for _ in range(9):
        chain.step((NAN, NAN, NAN), 1.0, DT, carried)
    assert chain.step((0.8, NAN, NAN), 1.0, DT, carried).vouched
    for _ in range(30):  # 0.6 s unseen: the chain ends, and the next reading is judged afresh
        chain.step((NAN, NAN, NAN), 0.0, DT, carried)
    assert math.isnan(chain.last_m) and chain.state == "none"


@pytest.mark.parametrize("field, value", [("gate_m", 0.0), ("gap_s", 11.0), ("confirm_frames", 0),
                                          ("seen_from_m", "far")])
def test_bad_settings_are_refused(field, value):
    with pytest.raises(ValueError, match=field):
        ChainConfig(**{field: value})


def _watched(chain: ReadingChain, seconds: float = 1.2) -> ReadingChain:
    """The chain after watching an empty lane this long."""
    nothing = CarriedTarget(Envelope())
    for _ in range(round(seconds / DT)):
        chain.step((NAN, NAN, NAN), 0.0, DT, nothing)
    return chain


def test_the_chain_follows_the_relative_motion_where_a_new_chain_would_be_implausible():
    chain, nothing = _watched(ReadingChain()), CarriedTarget(Envelope())
    # A car first seen at 1.6 m on a watched lane is plausible (the detector sees a QCar 2 from 1.5 m).
    assert chain.step((1.6, NAN, NAN), 0.0, DT, nothing).vouched
    for _ in range(9):  # closing at 1 m/s, unseen for 0.18 s
        chain.step((NAN, NAN, NAN), 1.0, DT, nothing)
    # 1.4 m is where the chain expects it: the same chain, still vouched (born afresh it would not be).
    assert chain.step((1.4, NAN, NAN), 1.0, DT, nothing).vouched
    assert _watched(ReadingChain()).step((1.4, NAN, NAN), 0.0, DT, nothing).implausible


def test_readings_that_are_no_range_are_no_reading():
    chain = ReadingChain()
    for readings in ((math.inf, NAN, NAN), (0.0, NAN, NAN), (-1.0, NAN, NAN)):
        assert not chain.step(readings, 0.0, DT, CarriedTarget(Envelope())).vouched
        assert math.isnan(chain.last_m)


def test_only_two_witnesses_that_agree_confirm_a_car_that_appeared():
    chain, carried = ReadingChain(), _carried(1.0)
    chain.step((1.0, 1.0, NAN), 0.0, DT, carried)
    # Depth and LiDAR 0.4 m apart: not a confirmation, however long.
    assert not any(chain.step((0.5, 0.9, NAN), 0.0, DT, carried).vouched for _ in range(10))
    fresh = ReadingChain()
    fresh.step((1.0, 1.0, NAN), 0.0, DT, carried)
    # Born implausible with two agreeing witnesses from its first frame: vouched on the third.
    assert [fresh.step((0.5, 0.52, NAN), 0.0, DT, carried).vouched for _ in range(3)] == [False, False, True]


def test_a_vouched_chain_that_walks_past_the_far_end_is_refused():
    chain, carried = ReadingChain(ChainConfig(noise_m=0.05)), _carried(1.0)
    chain.step((1.0, NAN, NAN), 0.0, DT, carried)
    carried.vouch(1.0, 0.0, lead_known=True)
    assert chain.step((carried.far_m + 0.04, NAN, NAN), 0.0, DT, carried).vouched
    walked = ReadingChain(ChainConfig(noise_m=0.05))
    walked.step((1.0, NAN, NAN), 0.0, DT, carried)
    carried.vouch(1.0, 0.0, lead_known=True)
    verdict = walked.step((carried.far_m + 0.06, NAN, NAN), 0.0, DT, carried)
    assert verdict.refused and walked.jumped


def test_a_jump_is_remembered_across_a_gap_until_the_target_is_seen_within_its_reach():
    chain, carried = ReadingChain(), _carried(1.0)
    chain.step((1.0, NAN, NAN), 0.0, DT, carried)
    chain.step((2.5, NAN, NAN), 0.0, DT, carried)  # a jump no car makes
    assert chain.jumped
    for _ in range(30):  # 0.6 s with no reading: the far end grows past 1.6 m, the reach does not
        chain.step((NAN, NAN, NAN), 0.0, DT, carried)
        carried.predict(0.0, DT)
    assert carried.far_m > 1.6 > carried.reach_m + agree_m(1.6)
    # Born within the far end but beyond the reach: refused (the gap does not launder the jump).
    assert chain.step((1.6, NAN, NAN), 0.0, DT, carried).refused
    for _ in range(30):
        chain.step((NAN, NAN, NAN), 0.0, DT, carried)
    # Seen again within its reach: vouched, and the jump forgotten.
    assert chain.step((1.0, NAN, NAN), 0.0, DT, carried).vouched and not chain.jumped
    carried.vouch(1.0, 0.6, lead_known=True)
    for _ in range(30):
        chain.step((NAN, NAN, NAN), 0.0, DT, carried)
        carried.predict(0.0, DT)
    # Within the reach (the target kept its speed): vouched; beyond it, within the far end: refused.
    assert chain.step((carried.reach_m - 0.01, NAN, NAN), 0.0, DT, carried).vouched
    for _ in range(30):
        chain.step((NAN, NAN, NAN), 0.0, DT, carried)
        carried.predict(0.0, DT)
    assert carried.far_m > carried.reach_m + 0.5
    assert chain.step((carried.reach_m + 0.4, NAN, NAN), 0.0, DT, carried).refused


def test_a_reset_forgets_a_jump():
    chain, carried = ReadingChain(), _carried(1.0)
    chain.step((1.0, NAN, NAN), 0.0, DT, carried)
    chain.step((2.5, NAN, NAN), 0.0, DT, carried)
    chain.reset()
    for _ in range(30):
        carried.predict(0.0, DT)
    assert not chain.jumped and chain.step((carried.reach_m, NAN, NAN), 0.0, DT, carried).vouched


def test_a_new_chain_farther_than_the_box_allows_is_refused_a_going_one_is_not():
    carried = _carried(1.0)
    assert ReadingChain().step((1.0, NAN, NAN), 0.0, DT, carried, size_m=0.95).vouched
    # Born 0.35 m beyond a box that says 0.8 m (its slack: 0.2 m): no car's range.
    refused = ReadingChain().step((1.15, NAN, NAN), 0.0, DT, carried, size_m=0.8)
    assert refused.refused
    # With no box, the same reading is the carried target's.
    assert ReadingChain().step((1.15, NAN, NAN), 0.0, DT, carried).vouched
    # A going chain under a box that grew (a phantom's picture): not consulted.
    going = ReadingChain()
    going.step((1.0, NAN, NAN), 0.0, DT, carried)
    assert going.step((1.0, NAN, NAN), 0.0, DT, carried, size_m=0.5).vouched


def test_the_slack_and_agreement_by_hand():
    from racf.experiments.car.supervisor.vouch import NOTHING, size_slack_m

    assert size_slack_m(0.5) == 0.2 and size_slack_m(2.0) == pytest.approx(0.4)
    assert agree_m(0.5) == 0.15 and agree_m(2.0) == pytest.approx(0.3)
    assert not (NOTHING.vouched or NOTHING.implausible or NOTHING.refused)


def test_the_default_chain_is_the_one_documented():
    import dataclasses

    assert dataclasses.asdict(ChainConfig()) == {"gate_m": 0.25, "gap_s": 0.5, "watch_s": 1.0, "seen_from_m": 1.5,
                                                 "confirm_frames": 3, "noise_m": 0.05}
    with pytest.raises(dataclasses.FrozenInstanceError):
        ChainConfig().gate_m = 1.0
    assert ChainConfig(gap_s=10.0).gap_s == 10.0
