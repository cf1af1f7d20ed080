"""The defence as a service: the same answers as in the car's process, one defence per car, a car
that survives a service dying mid-episode, and one line for a service that is not there."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest

from racf.errors import UserError
from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.link.remote import RemoteEstimator
from tests.conftest import run_cli


SPEC = TrialSpec("attack+odca", 1, 1.0, 3)


@pytest.mark.slow
def test_an_episode_through_the_service_is_the_episode_in_process(service):
    """The same distances, gate and brake, step by step, until an answer is late or missing (a loaded
    machine can make one overrun the 20 ms period, or even the car's timeout: the measured latency
    then delays the car, or it drives on its own depth, as it should)."""
    endpoint = service("odca")
    result, log = run_trial(replace(SPEC, estimator_endpoint=endpoint))
    expected, reference = run_trial(SPEC)
    late = np.flatnonzero(log["service_rtt_ms"].to_numpy() >= 20.0)
    fell = np.flatnonzero(log["service_fallback"].to_numpy() == 1.0)
    disturbed = np.concatenate([late, fell])
    upto = int(disturbed.min()) if disturbed.size else max(len(log), len(reference))  # its own action is held
    for column in ("d_fused", "w", "flag", "brake", "speed_cmd"):
        assert np.array_equal(log[column].to_numpy()[:upto], reference[column].to_numpy()[:upto], equal_nan=True), column
    row = result.to_dict()
    assert row["service_fallback_steps"] == fell.size and row["service_late_steps"] == late.size
    assert row["service_steps"] + fell.size == int(log["control"].sum()) and 0 < row["service_rtt_p50_ms"] < 20.0
    if not disturbed.size:
        assert {k: v for k, v in row.items() if not k.startswith(("service", "trial_id"))} == \
            {k: v for k, v in expected.to_dict().items() if k != "trial_id"}


@pytest.mark.parametrize("fallback", ["raw", "odca"])
def test_a_service_that_dies_mid_episode_is_survived_and_logged(service, fallback):
    endpoint = service("odca", max_requests=60)  # hello, calibrate, reset, then 57 answers
    result, log = run_trial(replace(SPEC, estimator_endpoint=endpoint, estimator_timeout_ms=20.0,
                                    estimator_fallback=fallback))
    fell_back = log["service_fallback"].to_numpy() == 1.0
    first = int(np.argmax(fell_back))
    assert fell_back.any() and fell_back[first:].all() and not fell_back[:first].any()
    assert result.service_fallback and result.service_fallback_steps == int(fell_back.sum())
    own = np.array_equal(log["d_fused"][fell_back].to_numpy(), log["d_meas"][fell_back].to_numpy(), equal_nan=True)
    onboard = log["service_onboard"].to_numpy() == 1.0
    if fallback == "raw":  # where it fell back the car drove on its own depth distance
        assert own and not onboard.any() and result.service_onboard_steps == 0
    else:  # on its onboard ODCA, which holds the distance where the depth has none
        assert not own and (onboard == fell_back).all() and result.service_onboard_steps == int(fell_back.sum())


def test_each_car_gets_its_own_defence(service):
    from racf.controllers import PerceptionSample

    endpoint = service("ekf")
    a, b = RemoteEstimator(endpoint, "ekf"), RemoteEstimator(endpoint, "ekf")
    for est in (a, b):
        est.reset()
    near = PerceptionSample(None, 1.0, 0.9, 1.0, 0.0)
    far = PerceptionSample(None, 3.0, 0.9, 3.0, 0.0)
    for _ in range(20):
        da, db = a.estimate(near, 0.0, 0.02), b.estimate(far, 0.0, 0.02)
    assert da < 1.5 < 2.5 < db
    a.close(), b.close()


def test_a_service_serving_another_defence_or_none_is_one_line(service, capsys):
    endpoint = service("raw")
    with pytest.raises(UserError, match="serves raw, not 'odca'"):
        RemoteEstimator(endpoint, "odca")
    code, _ = run_cli(["trial", "--setting", "attack+odca", "--estimator-endpoint", "tcp://127.0.0.1:9",
                       "--estimator-timeout-ms", "200"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "no defence service answers" in err
    # The service to start is the one asked for, where it was asked for: not the default port.
    assert "`racf serve --bind tcp://127.0.0.1:9 --defence odca`" in err


BRITTLE = '''
from racf.controllers.estimators import RawDepthEstimator


class Brittle(RawDepthEstimator):
    name = "brittle"

    def __init__(self):
        super().__init__()
        self.calls = 0

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0):
        self.calls += 1
        if self.calls == 5:
            raise RuntimeError("lost its footing")
        return super().estimate(sample, speed_mps, dt, yaw_rate_radps)
'''


def test_a_defence_that_raises_is_restarted_for_that_car_alone(service, tmp_path, plugin_env, caplog):
    from racf.controllers import PerceptionSample
    from racf.plugins import load_plugin_file

    path = tmp_path / "brittle.py"
    path.write_text(BRITTLE)
    load_plugin_file(path)
    endpoint = service(None)
    car, other = RemoteEstimator(endpoint, "brittle"), RemoteEstimator(endpoint, "raw")
    car.reset(), other.reset()
    sample = PerceptionSample(None, 1.5, 0.9, 1.4, 0.0)
    with caplog.at_level("WARNING", logger="racf.serve"):
        answers = [car.estimate(sample, 0.5, 0.02) for _ in range(10)]
        assert all(other.estimate(sample, 0.5, 0.02) == 1.5 for _ in range(10))
    # Rebuilt, it counts its calls afresh: it raises again at its own 5th (the car's 10th step).
    assert car.diagnostics()["service_restarts"] == 2.0 and car.restarts == 2
    assert car.diagnostics()["service_new_sessions"] == 0.0  # the session stood: only its defence was rebuilt
    assert answers == [1.5] * 10  # the 5th and 10th are the car's own depth: the same number, from the fallback
    assert "brittle raised in the session" in caplog.text and "lost its footing" in caplog.text
    car.close(), other.close()


def test_a_defence_the_service_lacks_is_refused_in_one_line_with_what_to_do(service):
    endpoint = service(None)
    with pytest.raises(UserError) as err:
        RemoteEstimator(endpoint, "tinfoil")
    words = str(err.value)
    assert "has no defence 'tinfoil'" in words and "racf serve --plugin" in words and "\n" not in words


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_service_killed_and_restarted_mid_episode_gets_a_new_session(service, unanswered_waits):
    """The first service stops answering after 60 requests; a new one listens on its port 0.5 s later
    (longer than the car's timeout, so that the car must fall back: restarted at once, the new
    service could answer the car's next request in time on a fast machine, and the test would race).
    The car falls back (each fallback step waits no longer than its timeout), asks again after
    retry_s of its own time, opens a new session and is answered again."""
    import threading
    import time

    endpoint = f"tcp://127.0.0.1:{_free_port()}"
    stops: list = []
    from tests.conftest import start_service

    start_service("odca", stops, max_requests=60, endpoint=endpoint)
    first_stop, first = stops[0]
    threading.Thread(target=lambda: (first.join(), time.sleep(0.5), start_service("odca", stops, endpoint=endpoint)),
                     daemon=True).start()
    waits = unanswered_waits  # how long the car waited each time no answer came, as it measured it
    timeout_ms = 100.0  # a loaded machine's answers stay within it (the default is 150 ms)
    try:
        result, log = run_trial(replace(SPEC, estimator_endpoint=endpoint, estimator_timeout_ms=timeout_ms))
    finally:
        for stop, thread in stops:
            stop.set()
            thread.join(5)
    fell_back = log["service_fallback"].to_numpy() == 1.0
    first_down = int(np.argmax(fell_back))
    back = first_down + int(np.argmax(~fell_back[first_down:]))
    # (Later fallbacks may be real timeouts of a loaded machine; the outage is the first run of them.)
    assert fell_back.any() and back > first_down and fell_back[first_down:back].all()
    assert log["service_new_sessions"].to_numpy()[back] == 1.0 and result.service_new_sessions >= 1
    assert result.service_restarts == 0  # the defence itself never raised: no defence restart
    # Each time the car went unanswered it waited its timeout and no longer (100 ms of scheduling slack):
    # the outage costs a step at most the timeout, never the 2 s a first answer may wait.
    assert waits and max(waits) <= timeout_ms + 100.0, waits


def test_an_episode_ends_its_session_with_a_goodbye(service, caplog):
    endpoint = service("raw")
    with caplog.at_level("INFO", logger="racf.serve"):
        run_trial(TrialSpec("clean", 1, 1.0, 3, run_up_m=0.6, estimator_endpoint=endpoint))
    assert "ended (the car closed it): raw" in caplog.text and "round trip" in caplog.text


def test_two_cars_interleaved_each_get_the_answers_of_their_own_odca(service):
    """ODCA's state is each car's: two approaches stepped in turn through one service give what each
    gives alone (a model shared between sessions mixed the two: braked early through the service)."""
    from racf.controllers import PerceptionSample
    from racf.experiments.car.estimators import make_estimator

    endpoint = service("odca")
    cars = [RemoteEstimator(endpoint, "odca"), RemoteEstimator(endpoint, "odca")]
    starts = (3.0, 1.8)

    def sample(i, k):
        d = starts[i] - 0.02 * k
        return PerceptionSample(None, d, 0.9, d + 0.05, 0.0)

    for car in cars:
        car.reset()
    served = [[], []]
    for k in range(60):  # the two cars' steps in turn
        for i in (0, 1):
            served[i].append(cars[i].estimate(sample(i, k), 1.0, 0.02))
    alone = make_estimator("odca")
    local = []
    for i in (0, 1):  # each approach on its own, one after the other
        alone.reset()
        local.append([alone.estimate(sample(i, k), 1.0, 0.02) for k in range(60)])
    assert np.array_equal(served, local, equal_nan=True)
    for car in cars:
        car.close()


def test_a_fallback_waits_the_timeout_in_milliseconds(service):
    """A car whose service is gone gets its answer (its own depth) after timeout_ms, not seconds."""
    import threading
    import time

    from racf.controllers import PerceptionSample

    car = RemoteEstimator(service("raw"), "raw", timeout_ms=30.0)
    car.reset()
    car._socket.close(0)  # the link cut: nothing answers on a fresh socket to a closed port
    car._socket, car.endpoint = None, "tcp://127.0.0.1:9"
    took = []

    def ask():
        start = time.perf_counter()
        car.estimate(PerceptionSample(None, 1.5, 0.9, 1.4, 0.0), 0.5, 0.02)
        took.append(time.perf_counter() - start)

    thread = threading.Thread(target=ask, daemon=True)
    thread.start()
    thread.join(2.0)
    assert took and took[0] < 0.03 + 0.5, "the fallback waited far longer than its timeout"
    assert car.diagnostics()["service_fallback"] == 1.0


def test_a_service_restarted_between_two_requests_opens_a_new_session(service):
    """The service stops and another takes its port between two steps: the car's socket reconnects,
    the new service answers "no session", and the car opens one and asks again, with no fallback."""
    import threading

    from racf.controllers import PerceptionSample
    from tests.conftest import start_service

    endpoint = f"tcp://127.0.0.1:{_free_port()}"
    stops: list = []
    start_service("raw", stops, endpoint=endpoint)
    car = RemoteEstimator(endpoint, "raw", timeout_ms=3000.0)
    car.reset()
    sample = PerceptionSample(None, 1.5, 0.9, 1.4, 0.0)
    assert car.estimate(sample, 0.5, 0.02) == 1.5
    stop, thread = stops.pop()
    stop.set()
    thread.join(5)
    for attempt in range(100):  # ZeroMQ lets the old listener go in its I/O thread, a moment after close
        try:
            start_service("raw", stops, endpoint=endpoint)
            break
        except AssertionError:
            time.sleep(0.05)
    # The car's socket notices the old peer gone and reconnects in ZeroMQ's I/O thread (every 0.1 s): a
    # request sent before it has would wait out its timeout on the dead pipe, which is a fallback, not a restart.
    time.sleep(0.5)
    try:
        assert car.estimate(sample, 0.5, 0.02) == 1.5
        assert car.diagnostics()["service_fallback"] == 0.0 and car.new_sessions == 1 and car.restarts == 0
    finally:
        car.close()
        for stop, thread in stops:
            stop.set()
            thread.join(5)
