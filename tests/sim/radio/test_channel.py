"""The radio: it sends at its rate, delivers after its latency, loses what it should, and draws the same
from the same seed."""

from __future__ import annotations

import numpy as np
import pytest

from racf.sim.radio import RADIO_SLOTS, SIGNED_BYTES, Broadcast, Radio, RadioConfig, open_signed

LEAD = Broadcast(1, 2.0, 0.0, 0.0, 0.6, 0.0, False)


def _run(radio: Radio, seconds: float, receiver=(0.0, 0.0), dt=0.02):
    got = []
    for k in range(int(round(seconds / dt)) + 1):
        rows, times = radio.tick(k * dt, (LEAD,), receiver)
        assert rows.shape == (RADIO_SLOTS * SIGNED_BYTES,) and times.shape == (RADIO_SLOTS,)
        for i in range(RADIO_SLOTS):
            row = rows[i * SIGNED_BYTES:(i + 1) * SIGNED_BYTES]
            if row.any():
                got.append((k * dt, times[i], open_signed(row.tobytes(), radio.fleet.trust_store()).message))
    return got


def test_it_sends_at_its_rate_and_each_message_arrives_after_its_latency_signed_and_numbered():
    radio = Radio(RadioConfig(loss=0.0, latency_s=0.03, jitter_s=0.0))
    radio.reset(np.random.default_rng(0))
    got = _run(radio, 2.0)
    assert len(got) == 20  # 10 Hz for 2 s (the last one still in flight)
    assert [m.seq for _, _, m in got] == list(range(1, 21))
    for read_at, arrived, message in got:
        assert arrived == pytest.approx(message.t_s + 0.03) and read_at >= arrived
        assert abs(message.state.x_m - 2.0) < 0.2 and message.state.sender == 1  # the sender's own small error


def test_a_lossy_radio_loses_about_its_share_and_one_out_of_range_loses_all():
    radio = Radio(RadioConfig(loss=0.3))
    radio.reset(np.random.default_rng(1))
    got = _run(radio, 60.0)
    assert 0.6 * 600 < len(got) < 0.8 * 600
    far = Radio(RadioConfig(range_m=1.0))
    far.reset(np.random.default_rng(1))
    assert _run(far, 2.0, receiver=(10.0, 0.0)) == [] and far.sent == 1  # sent, and heard by no one


def test_the_same_seed_gives_the_same_bytes():
    def bytes_of(seed):
        radio = Radio()
        radio.reset(np.random.default_rng(seed))
        return [radio.tick(k * 0.02, (LEAD,), (0.0, 0.0))[0].tobytes() for k in range(60)]

    assert bytes_of(3) == bytes_of(3) != bytes_of(4)


@pytest.mark.parametrize("field,value", [("hz", 0.0), ("loss", 1.5), ("latency_s", -0.1), ("range_m", True)])
def test_a_bad_setting_names_itself(field, value):
    with pytest.raises(ValueError, match=f"radio {field} must be"):
        RadioConfig(**{field: value})


def test_more_than_the_car_can_take_in_a_step_is_cut_and_counted():
    radio = Radio(RadioConfig(loss=0.0, latency_s=0.05, jitter_s=0.0))
    radio.reset(np.random.default_rng(0))
    many = tuple(Broadcast(s, 2.0, 0.0, 0.0, 0.5, 0.0, False) for s in range(1, 9)) * 2  # 16 at once
    assert radio.tick(0.0, many, (0.0, 0.0))[1].tolist() == [0.0] * RADIO_SLOTS and radio.sent == 16
    rows, times = radio.tick(0.06, (), (0.0, 0.0))
    assert radio.delivered == RADIO_SLOTS and np.all(times == pytest.approx(0.05)) and radio.sent == 0
    assert radio.tick(0.08, (), (0.0, 0.0))[0].any() == False  # noqa: E712  (the rest were lost, not held)


def test_it_sends_on_its_own_clock_not_every_step():
    radio = Radio(RadioConfig(hz=5.0, loss=0.0))
    radio.reset(np.random.default_rng(0))
    sent = []
    for k in range(50):
        radio.tick(k * 0.02, (LEAD,), (0.0, 0.0))
        sent.append(radio.sent)
    assert sum(sent) == 5 and [k for k, s in enumerate(sent) if s] == [0, 10, 20, 30, 40]


@pytest.mark.parametrize("field,edge", [("hz", 0.5), ("hz", 50.0), ("loss", 0.0), ("loss", 1.0), ("range_m", 1000.0),
                                        ("latency_s", 1.0), ("jitter_s", 0.0), ("position_std_m", 1.0),
                                        ("speed_std_mps", 1.0)])
def test_each_setting_takes_its_edges(field, edge):
    assert getattr(RadioConfig(**{field: edge}), field) == edge
