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
