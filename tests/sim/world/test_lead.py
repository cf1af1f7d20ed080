"""The lead car's motion: its profiles, the stop line it obeys, and its reset option."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.sim.world.lead import LAUNCH_MPS2, LEAD_PROFILES, STOP_AND_GO_WAIT_S, LeadCar
from racf.sim.world.stop_signs import stop_signs
from racf.sim.world.traffic import TRAFFIC_BRAKE_MPS2

ROUTE = stop_signs()[1].route
T = np.arange(0.0, 20.0, 0.01)


def lead(**kw) -> LeadCar:
    args = {"route": ROUTE, "start_s": 1.0, "speed_mps": 0.6, "stop_s": 7.0, "profile": "hard_brake",
            "decel_mps2": 3.0, "brake_t_s": 3.0, **kw}
    return LeadCar(**args)


def test_a_hard_brake_stops_at_its_deceleration_and_stays():
    s, v = lead().profile_at(T)
    assert v[T < 3.0] == pytest.approx(0.6)
    stopped = 3.0 + 0.6 / 3.0
    assert v[(T > 3.05) & (T < stopped - 0.02)] == pytest.approx(0.6 - 3.0 * (T[(T > 3.05) & (T < stopped - 0.02)] - 3.0), abs=0.01)
    assert np.all(v[T > stopped + 0.01] == 0) and s[-1] == pytest.approx(1.0 + 0.6 * 3.0 + 0.6**2 / 6, abs=0.01)


def test_a_cruising_lead_stops_at_the_line_braking_as_traffic_does():
    s, v = lead(profile="cruise").profile_at(T)
    assert s.max() == pytest.approx(7.0, abs=1e-3) and v[-1] == 0.0
    at = np.flatnonzero(v < 0.6 - 1e-6)[0]
    assert 7.0 - s[at] == pytest.approx(0.6**2 / (2 * TRAFFIC_BRAKE_MPS2), abs=0.01)


def test_stop_and_go_waits_then_pulls_away():
    _, v = lead(profile="stop_and_go", stop_s=10.3).profile_at(T)
    go = 3.0 + 0.6 / 3.0 + STOP_AND_GO_WAIT_S
    assert np.all(v[(T > 3.25) & (T < go)] == 0)
    assert v[np.searchsorted(T, go + 0.3)] == pytest.approx(LAUNCH_MPS2 * 0.3, abs=0.02)
    assert v[np.searchsorted(T, go + 2.0)] == pytest.approx(0.6)


def test_slow_down_settles_at_half_its_speed():
    _, v = lead(profile="slow_down", stop_s=10.3).profile_at(T[T < 8])
    assert v[-1] == pytest.approx(0.3)


@settings(max_examples=40, deadline=None)
@given(profile=st.sampled_from(LEAD_PROFILES), speed=st.floats(0.0, 3.0), decel=st.floats(0.1, 8.0),
       brake=st.floats(0.0, 10.0), start=st.floats(0.0, 6.0))
def test_it_never_reverses_speeds_or_passes_its_line(profile, speed, decel, brake, start):
    car = lead(profile=profile, speed_mps=speed, decel_mps2=decel, brake_t_s=brake, start_s=start)
    s, v = car.profile_at(T[::10])
    assert np.all(np.diff(s) >= -1e-9) and np.all(v >= 0) and np.all(v <= speed + 1e-9)
    assert s.max() <= 7.0 + 1e-9 and s[0] == pytest.approx(start)


def test_its_option_round_trips_and_a_bad_one_says_what_it_needs():
    car = lead(colour="blue")
    assert LeadCar.from_options(car.to_options()) == car
    with pytest.raises(ValueError, match="exactly"):
        LeadCar.from_options({"route": list(ROUTE)})
    with pytest.raises(ValueError, match="profile must be one of"):
        lead(profile="swerve")
    with pytest.raises(ValueError, match="start_s <= stop_s"):
        lead(start_s=8.0)
    assert math.isfinite(car.states(np.array([1.0]))[0, 0])
