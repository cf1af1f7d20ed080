"""The link's man in the middle: answers held, lost or replaced on a plain link; on a CurveZMQ link a
replaced answer never reaches the car, which falls back to its own depth and logs the refusal."""

from __future__ import annotations

import struct
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.link.curve import ServerKeys, make_keys
from racf.experiments.link.relay import ZmtpFrames, frame_bytes

ALWAYS = {"trigger": "always"}
#: On from the first step to the end of the episode.
WHOLE = {"t_atk": (60.0, 60.0)}


@given(st.lists(st.tuples(st.binary(max_size=600), st.sampled_from([0, 1, 4, 5])), max_size=6),
       st.integers(1, 97))
def test_frames_are_cut_where_zmtp_puts_them_whatever_the_reads(frames, chunk):
    """The greeting, then each frame whole (short and long sizes), however the bytes arrive."""
    greeting = bytes(range(64))
    stream = greeting + b"".join(frame_bytes(body, flags) for body, flags in frames)
    cutter, pieces = ZmtpFrames(), []
    for at in range(0, len(stream), chunk):
        pieces += cutter.feed(stream[at:at + chunk])
    assert b"".join(raw for raw, flags, _ in pieces if flags == -1) == greeting
    assert [(body, flags & ~0x02) for _, flags, body in pieces if flags != -1] == [(b, f) for b, f in frames]
    assert b"".join(raw for raw, _, _ in pieces) == stream


def test_a_long_frame_carries_an_eight_byte_size():
    raw = frame_bytes(b"x" * 300, 0)
    assert raw[0] == 0x02 and struct.unpack(">Q", raw[1:9])[0] == 300 and len(raw) == 309


@pytest.fixture(scope="module")
def keys(tmp_path_factory):
    root = tmp_path_factory.mktemp("link-keys")
    make_keys(root)
    return root


def spoof(endpoint: str, **fields) -> TrialSpec:
    return TrialSpec("clean+link_spoof", 1, 1.0, 3, attack_params={"link_spoof": {**ALWAYS, "distance_m": 7.5}},
                     estimator_endpoint=endpoint, estimator_timeout_ms=500.0, **WHOLE, **fields)


def test_a_spoofed_distance_reaches_a_car_on_a_plain_link_and_its_own_witnesses_outvote_it(service):
    result, log = run_trial(spoof(service("raw")))
    answered = log["control"].astype(bool) & (log["service_fallback"] == 0.0)
    assert answered.sum() > 20
    # The attacker's distance reaches every answer from the first step on (the schedule opens at the first
    # step): it drives where the car's onboard defence sees nothing nearer, and is outvoted where it does.
    outvoted = np.diff(log["service_outvoted"].to_numpy(float), prepend=0.0) > 0
    spoofed = log["d_fused"] == 7.5
    assert np.all((spoofed | outvoted)[answered].iloc[1:])
    assert outvoted[answered].sum() > 20 and log["service_refusals"].max() == 0
    assert result.success  # the lie cost the car nothing: it stopped at the sign


@pytest.mark.slow  # an episode through a relay on a CurveZMQ link: about 12 s
def test_a_spoofed_answer_never_reaches_a_car_on_an_authenticated_link(service, keys):
    endpoint = service("raw", keys=ServerKeys.load(keys))
    result, log = run_trial(spoof(endpoint, estimator_keys=str(keys)))
    control = log["control"].astype(bool)
    assert not (log.loc[control, "d_fused"] == 7.5).any()
    fell_back = control & (log["service_fallback"] == 1.0)
    assert fell_back.any()
    # Where it fell back the car drove on its onboard defence (ODCA, by default), and it logged why.
    assert (log.loc[fell_back, "service_onboard"] == 1.0).all() and result.service_onboard_steps == int(fell_back.sum())
    assert log["service_refusals"].max() >= 1


@pytest.mark.slow  # two episodes through a relay: about 12 s
def test_a_dropped_answer_is_a_fallback_and_a_delayed_one_a_late_step(service):
    endpoint = service("raw")
    spec = TrialSpec("clean+link_drop", 1, 1.0, 3, attack_params={"link_drop": ALWAYS}, estimator_endpoint=endpoint,
                     estimator_timeout_ms=40.0, **WHOLE)
    _, log = run_trial(spec)
    control = log["control"].astype(bool)
    assert (log.loc[control, "service_fallback"].iloc[1:] == 1.0).all()  # after the schedule opened
    spec = TrialSpec("clean+link_delay", 1, 1.0, 3, estimator_endpoint=endpoint, estimator_timeout_ms=500.0, **WHOLE,
                     attack_params={"link_delay": {**ALWAYS, "delay_ms": 45.0, "jitter_ms": 0.0}})
    result, log = run_trial(spec)
    rtt = log.loc[log["control"].astype(bool), "service_rtt_ms"].iloc[1:]
    assert rtt.min() >= 45.0 and result.service_late_steps >= rtt.size  # each answer overran the 20 ms period
    assert result.service_invalid == 0  # held, not reordered: each answer names its own request


def test_a_link_attack_needs_a_link():
    with pytest.raises(ValueError, match="link_drop attacks the link to a defence service"):
        TrialSpec("clean+link_drop", 1, 1.0, 3)
