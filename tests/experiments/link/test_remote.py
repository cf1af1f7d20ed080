"""The car trusts nothing a service sends: an answer counts only if the protocol's check passes it,
anything else is a counted fallback step on the car's own depth, and nothing a service says ends
an episode."""

from __future__ import annotations

import logging
import math
import socket
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from racf.controllers import PerceptionSample
from racf.errors import UserError
from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.link.remote import RemoteEstimator
from racf.experiments.link.wire import DISTANCE_RANGE_M, PROTOCOL, InvalidAnswer, check_answer
from tests.experiments.link.fake_service import IN_RANGE_LIES, LIES, FakeService


def _sample(k: int) -> PerceptionSample:
    d = 3.0 - 0.02 * k
    return PerceptionSample(None, d, 0.9, d + 0.05, 0.0)


def _drive(car: RemoteEstimator, steps: int) -> tuple[list[float], list[dict]]:
    car.reset()
    out, diagnostics = [], []
    for k in range(steps):
        out.append(car.estimate(_sample(k), 1.0, 0.02))
        diagnostics.append(car.diagnostics())
    return out, diagnostics


@pytest.mark.parametrize("lie", [name for name in LIES if name not in IN_RANGE_LIES])
def test_every_lie_is_a_counted_fallback_on_the_cars_own_depth(lie, caplog):
    with FakeService(lie, honest=30) as fake, caplog.at_level(logging.WARNING, logger="racf.link"):
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=5000.0, retry_s=0.1)
        distances, diagnostics = _drive(car, 80)
        car.close()
    # Honest or not, every step's distance is the car's own depth here (the fake answers d_meas honestly).
    assert np.allclose(distances, [_sample(k).d_meas for k in range(80)])
    fell = [d["service_fallback"] for d in diagnostics]
    assert fell[:30] == [0.0] * 30 and all(fell[30:])  # every step after the first lie is no answer
    assert fake.lies >= 3 and car.invalid == fake.lies == diagnostics[-1]["service_invalid"]
    assert car.new_sessions == fake.lies - 1 and car.restarts == 0  # each lie: a pause, then a new session
    assert car.refusals == 0 and diagnostics[-1]["service_refusals"] == 0.0  # a lie is no failed handshake
    assert car.n_parameters == 0  # a service that names no parameters has none
    assert 0.005 < diagnostics[0]["service_rtt_ms"] < 1000.0  # a loopback round trip, in milliseconds
    lines = [r for r in caplog.records if "falls back" in r.getMessage()]
    assert len(lines) == 1  # the first lie of its kind said once, not once a step


def test_a_step_that_asks_nothing_waits_for_nothing():
    with FakeService("nan", honest=1) as fake:
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=5000.0, retry_s=0.1)
        car.reset()
        car.estimate(_sample(0), 1.0, 0.02)
        car.estimate(_sample(1), 1.0, 0.02)  # the lie: the car pauses for retry_s of its own time
        car.estimate(_sample(2), 1.0, 0.02)
        assert car.latency_s == 0.0 and car.diagnostics()["service_fallback"] == 1.0
        car.close()


def test_no_target_is_said_explicitly_and_read_as_nan():
    with FakeService(None) as fake:
        car = RemoteEstimator(fake.endpoint, "raw")
        car.reset()
        assert math.isnan(car.estimate(PerceptionSample(None, math.nan, 0.0, math.nan, math.nan), 1.0, 0.02))
        assert car.diagnostics()["service_fallback"] == 0.0
        car.close()


#: What a service can send: anything msgpack carries (its integers lie in [-2**63, 2**64 - 1]).
ints = st.integers(-2**63, 2**64 - 1)
answers = st.dictionaries(st.sampled_from(["id", "distance", "stands", "diagnostics", "error", "restarted",
                                           "no_session"]),
                          st.none() | st.booleans() | ints | st.integers(-5, 60) | st.floats() | st.text(max_size=5)
                          | st.lists(ints, max_size=2) | st.dictionaries(st.text(max_size=3), st.floats(), max_size=2),
                          max_size=7)


@settings(max_examples=300, deadline=None)
@given(answers, st.integers(0, 10))
def test_an_answer_passes_the_check_only_if_the_protocol_allows_it(reply, request_id):
    try:
        checked = check_answer("estimate", reply, request_id)
    except InvalidAnswer as err:
        assert err.kind in {"stale", "error", "no_session", "restarted", "missing", "wrong_type", "out_of_range"}
        return
    lo, hi = DISTANCE_RANGE_M
    assert reply["id"] == request_id and not isinstance(reply["id"], bool)
    assert "error" not in reply and "restarted" not in reply
    d = checked["distance"]
    assert d is None or (isinstance(d, float) and lo <= d <= hi)
    assert checked["stands"] in (None, True, False)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(answers)
def test_whatever_a_service_answers_the_car_acts_on_a_checked_distance_or_its_own_depth(reply):
    def lie(rid, honest):  # a drawn id of 0, or none, names the request; any other id is another's
        named = reply.get("id", 0)
        return {**reply, "id": rid if named == 0 and not isinstance(named, bool) else named}

    with FakeService(lie, honest=0) as fake:
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=5000.0)
        car.reset()
        d = car.estimate(_sample(0), 1.0, 0.02)
        fell = car.diagnostics()["service_fallback"] == 1.0
        car.close()
    lo, hi = DISTANCE_RANGE_M
    if fell:  # refused by the check, or the service said it rebuilt its defence
        assert d == _sample(0).d_meas and car.invalid + car.restarts == 1
    else:
        assert math.isnan(d) or lo <= d <= hi
        assert car.invalid == car.restarts == 0


def test_a_protocol_1_service_is_refused_in_one_line():
    with FakeService(pong={"pong": True}) as fake:
        with pytest.raises(UserError) as err:
            RemoteEstimator(fake.endpoint, "raw")
    assert f"speaks protocol 1 (it names none); this car speaks {PROTOCOL}" in str(err.value)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("what, hellos", [
    ("a refused re-hello", lambda n, honest: honest if n == 1 else {"refused": "full", "id": honest["id"]}),
    ("a re-hello never answered", lambda n, honest: honest if n == 1 else None),
    ("a re-hello answered with an error", lambda n, honest: honest if n == 1 else {"error": "x", "id": honest["id"]}),
])
def test_a_failed_new_session_is_a_fallback_and_the_car_keeps_trying(what, hellos):
    with FakeService("error", honest=5, hellos=hellos) as fake:
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=100.0, retry_s=0.1)
        distances, diagnostics = _drive(car, 40)
        car.close()
    assert np.allclose(distances, [_sample(k).d_meas for k in range(40)])
    assert all(d["service_fallback"] == 1.0 for d in diagnostics[5:])
    assert fake.hellos >= 4 and car.new_sessions == 0  # it kept asking, on its retry period, and never got one
    assert car.refusals == 0  # a silence or a no is not a failed handshake


def test_a_late_service_and_no_service_are_two_lines(caplog):
    with FakeService(ping_delay_s=5.0) as fake:  # listens, but answers nothing within connect_s
        with pytest.raises(UserError) as late:
            RemoteEstimator(fake.endpoint, "raw", connect_s=2.5)
    # A port held bound but not listening: nothing answers there, and no other test can take it meanwhile.
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        with pytest.raises(UserError) as silent:
            RemoteEstimator(f"tcp://127.0.0.1:{held.getsockname()[1]}", "raw", connect_s=2.5)
    assert "answers late" in str(late.value) and "--estimator-timeout-ms" in str(late.value)
    assert "round trip seen: none" in str(late.value) and "nothing listens" not in str(late.value)
    assert "nothing listens there" in str(silent.value) and "answers late" not in str(silent.value)
    with FakeService(ping_delay_s=0.3) as fake, caplog.at_level(logging.WARNING, logger="racf.link"):
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=100.0)  # late, but there: it drives, warned
        car.close()
    assert "answers late: its first answer took" in caplog.text and "--estimator-timeout-ms" in caplog.text


#: The paper's protocol, through a lying service: sign 1 at 1 m/s, seed 3.
SPEC = TrialSpec("clean", 1, 1.0, 3)


def _outcome(result) -> dict:
    return {k: v for k, v in result.to_dict().items() if not k.startswith(("service", "trial_id"))}


def _lying_episode(lie: str):
    with FakeService(lie, honest=30) as fake:
        result, log = run_trial(replace(SPEC, estimator_endpoint=fake.endpoint, estimator_timeout_ms=5000.0,
                                        estimator_fallback="raw"))
        return result, log, fake.lies


class _Onboard:
    """An onboard defence that says its depth plus 1 m and counts what it was shown."""

    name = "plus_one"

    def __init__(self) -> None:
        self.seen, self.resets = [], 0

    def reset(self) -> None:
        self.resets += 1

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0) -> float:
        self.seen.append(sample.d_meas)
        return sample.d_meas + 1.0

    def diagnostics(self) -> dict:
        return {"w": 0.25}


def test_where_the_service_gives_no_answer_the_onboard_defence_drives_having_seen_every_step(caplog):
    onboard = _Onboard()
    with FakeService("nan", honest=30) as fake, caplog.at_level(logging.WARNING, logger="racf.link"):
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=5000.0, retry_s=0.1, onboard=onboard)
        distances, diagnostics = _drive(car, 80)
        car.close()
    own = [_sample(k).d_meas for k in range(80)]
    fell = np.array([d["service_fallback"] for d in diagnostics]) == 1.0
    assert not fell[:30].any() and fell[30:].all()
    # The service's answers where it gave them (the fake answers d_meas), the onboard defence's elsewhere.
    assert np.allclose(np.array(distances)[~fell], np.array(own)[~fell])
    assert np.allclose(np.array(distances)[fell], np.array(own)[fell] + 1.0)
    assert [d["service_onboard"] for d in diagnostics] == [float(f) for f in fell]
    assert all(d["w"] == 0.25 for d, f in zip(diagnostics, fell) if f)  # the onboard defence's own diagnostics
    assert onboard.seen == own and onboard.resets == 1  # every step, served or not: its state is the episode's
    assert "falls back to its onboard defence (plus_one)" in caplog.text


def test_the_fallback_is_the_onboard_odca_by_default_and_checked():
    assert replace(SPEC, estimator_endpoint="tcp://127.0.0.1:9").estimator_fallback == "odca"
    assert "estimator_fallback" not in SPEC.to_dict()  # in the car's process there is no fallback
    with pytest.raises(ValueError, match="estimator_fallback must be 'raw'"):
        replace(SPEC, estimator_endpoint="tcp://127.0.0.1:9", estimator_fallback="telepathy")
    ids = {replace(SPEC, estimator_endpoint="tcp://127.0.0.1:9", estimator_fallback=f).trial_id for f in ("raw", "odca")}
    assert len(ids) == 2  # what drove where the service did not is part of what ran


@pytest.fixture(scope="module")
def own_depth():
    """The car's own depth fallback for the same seed: the raw defence, in the car's process."""
    return run_trial(SPEC)


def _check_lying_episode(lie: str, own_depth) -> None:
    result, log, lies = _lying_episode(lie)
    expected, _ = own_depth
    control = log["control"].astype(bool).to_numpy()
    fell = log["service_fallback"].to_numpy()[control] == 1.0
    assert not fell[:30].any() and fell[30:].all()
    row = result.to_dict()
    assert lies >= 1 and row["service_invalid"] == lies and row["service_fallback_steps"] == int(fell.sum())
    late = np.flatnonzero(log["service_rtt_ms"].to_numpy() >= 20.0)
    if not late.size:  # a loaded machine's late answer delays the car, as it should: then only the counts hold
        assert _outcome(result) == _outcome(expected)


@pytest.mark.parametrize("lie", ["nan", "stale"])
def test_a_lying_service_leaves_the_outcome_of_the_cars_own_depth(lie, own_depth):
    _check_lying_episode(lie, own_depth)


@pytest.mark.slow
@pytest.mark.parametrize("lie", ["negative", "inf", "far", "string", "error"])
def test_every_lie_leaves_the_outcome_of_the_cars_own_depth(lie, own_depth):
    _check_lying_episode(lie, own_depth)


def test_racf_trial_says_what_the_service_did_with_one_name_for_each_count(tmp_path, capsys):
    from tests.conftest import run_cli

    with FakeService("far", honest=30) as fake:
        code, _ = run_cli(["trial", "--setting", "clean", "--sign", "1", "--speed", "1.0", "--seed", "3",
                           "--estimator-endpoint", fake.endpoint, "--estimator-timeout-ms", "5000",
                           "--out", str(tmp_path)])
        lies = fake.lies
    err = capsys.readouterr().err
    assert code == 0
    assert f"({lies} answers refused by the protocol's check, 0 defence restarts, {lies - 1} new sessions)" in err


def test_a_car_that_cannot_be_answered_passes_and_closes_quietly():
    fake = FakeService(None)
    car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=200.0)
    car.reset()
    assert car.would_pass(depth=1.0, speed_mps=1.0, dt=0.02) is True  # the fake answers no "answer": none
    assert car.invalid == 1
    fake.stop()
    car._needs_session = False  # as if its session stood: the goodbye finds no one
    car._socket = car._socket or car._open()
    car.close()  # no raise: a goodbye is a courtesy


def test_a_service_that_starts_listening_a_moment_late_is_reached():
    """The first answer is waited for 2 s before the car says nothing listens: a service that binds
    0.5 s after the car starts asking is reached."""
    import socket
    import threading
    import time

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    started = []
    threading.Thread(target=lambda: (time.sleep(0.5), started.append(FakeService(None, port=port))),
                     daemon=True).start()
    try:
        car = RemoteEstimator(f"tcp://127.0.0.1:{port}", "raw", connect_s=10.0)
        car.close()
    finally:
        time.sleep(0.6)
        for fake in started:
            fake.stop()


def test_a_service_that_lost_the_session_gets_one_new_session_and_the_car_drives_on():
    told = []

    def forgot_once(rid, honest):  # the 31st estimate: "no session" (a service restarted); then honest again
        if told:
            return honest
        told.append(rid)
        return {"id": rid, "error": "no session: say hello first", "no_session": True}

    with FakeService(forgot_once, honest=30) as fake:
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=5000.0)
        distances, diagnostics = _drive(car, 45)
        car.close()
    # (The fake lies once, then tells the truth; the car asked again in a new session within the step.)
    assert all(d["service_fallback"] == 0.0 for d in diagnostics[31:]) and car.new_sessions == 1
    assert np.allclose(distances, [_sample(k).d_meas for k in range(45)])


def test_a_step_that_waited_out_its_timeout_is_as_late_as_its_wait():
    hellos = lambda n, honest: honest if n == 1 else None  # noqa: E731 - the service never opens a second session
    with FakeService("error", honest=1, hellos=hellos) as fake:
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=100.0, retry_s=0.02)
        car.reset()
        car.estimate(_sample(0), 1.0, 0.02)  # honest
        car.estimate(_sample(1), 1.0, 0.02)  # an error: the car waits retry_s of its own time
        car.estimate(_sample(2), 1.0, 0.02)  # a new hello, never answered: it waited its timeout
        assert car.diagnostics()["service_fallback"] == 1.0 and 0.09 <= car.latency_s < 1.0
        car.close()


# -- a served answer is one more reading (issue 78) --------------------------------------------------
from racf.experiments.link.remote import OUTVOTE_M, outvote  # noqa: E402

NAN = math.nan


@pytest.mark.parametrize("served, served_stands, own, own_stands, expected", [
    (1.0, True, 1.0, True, (1.0, True, False)),            # they agree: the service's
    (1.0 + OUTVOTE_M, None, 1.0, None, (1.15, None, False)),  # farther by the tolerance: still the service's
    (1.2, None, 1.0, None, (1.0, None, True)),             # farther by more: the car's own, outvoted
    (0.5, None, 1.0, None, (0.5, None, False)),            # nearer: on the safe side, the service's
    (NAN, None, 1.0, None, (1.0, None, True)),             # "no target" where the car sees one: outvoted
    (4.0, False, NAN, True, (4.0, True, True)),            # nothing stands, the car's own witnesses see it stand
    (4.0, False, NAN, False, (4.0, False, False)),         # nothing stands, nor do the car's witnesses say so
])
def test_a_served_answer_farther_than_the_cars_own_is_outvoted_by_hand(served, served_stands, own, own_stands,
                                                                     expected):
    got = outvote(served, served_stands, own, own_stands)
    assert got[1:] == expected[1:] and (got[0] == pytest.approx(expected[0]) or math.isnan(expected[0]))


def _served_lie_at_the_sign(lie: str):
    with FakeService(lie, honest=30) as fake:
        result, log = run_trial(replace(SPEC, estimator_endpoint=fake.endpoint, estimator_timeout_ms=5000.0,
                                        estimator_fallback="raw"))
        return result, log, fake.lies


def test_a_served_lie_in_range_is_outvoted_and_the_car_stops_at_the_sign():
    result, log, lies = _served_lie_at_the_sign("always 4 m")
    row = result.to_dict()
    assert lies > 30 and row["service_invalid"] == 0 and row["service_fallback_steps"] == 0
    assert row["service_outvoted"] > 0 and result.success, row


@pytest.mark.slow
@pytest.mark.parametrize("lie", ["3 m farther", "nothing stands"])
def test_every_served_lie_in_range_leaves_the_car_stopping(lie):
    result, _, lies = _served_lie_at_the_sign(lie)
    assert lies > 30 and result.to_dict()["service_outvoted"] > 0 and result.success


class _Standing(_Onboard):
    """An onboard defence whose own witnesses say a target stands."""

    def stands(self) -> bool:
        return True


def test_during_a_fallback_the_onboard_defence_s_verdict_stands_and_late_in_the_episode_the_pause_is_retry_s():
    """After 10 s of the car's own time a lie: the car falls back to its onboard defence, whose "a target
    stands" is the car's; it asks again only 0.1 s (retry_s) later, not at once on every step."""
    with FakeService("nan", honest=500) as fake:
        car = RemoteEstimator(fake.endpoint, "raw", timeout_ms=5000.0, retry_s=0.1, onboard=_Standing())
        car.reset()
        for k in range(500):  # 10 s at 50 Hz, every answer honest
            car.estimate(_sample(k % 100), 1.0, 0.02)
        hellos = fake.hellos
        fell = []
        for k in range(12):  # the lie, then 0.1 s (5 steps) without asking, then a new session
            car.estimate(_sample(k), 1.0, 0.02)
            fell.append(car.diagnostics()["service_fallback"])
            if k == 0:
                assert car.stands() is True  # the onboard defence's verdict, not dropped
        car.close()
    assert fell[:5] == [1.0] * 5 and fake.hellos == hellos + 1  # one new session after the pause, not one a step
