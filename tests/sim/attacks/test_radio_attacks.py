"""The attacks on the car ahead's broadcast, each against the car's receiver: forged and replayed messages
are refused, delayed ones go stale, jammed ones never come, and an insider's lie is accepted as what it is:
the lead's own signed word."""

from __future__ import annotations

from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from racf.experiments.car.broadcast import BroadcastReceiver
from racf.sim.attacks import ATTACKS
from racf.sim.radio import RADIO_SLOTS, SIGNED_BYTES, Broadcast, FleetKeys, RadioConfig, V2VMessage, sign
from racf.sim.world.manager import WorldTarget
from tests.conftest import TEST_FLEET

DT = 0.02
LEAD = WorldTarget("lead", "vehicle", "lead_0", ("lead_x", "lead_y", "lead_yaw"), (0.425, 0.192, 0.2))


class _Lead:
    def targets(self):
        return (LEAD,)


class RadioEnv(gym.Env):
    """The env's observation, empty but for the radio: the lead 2 m ahead at 0.5 m/s says so at 10 Hz,
    each message arriving 20 ms after it is sent."""

    world = (_Lead(),)

    def __init__(self) -> None:
        self.observation_space = spaces.Dict({
            "rgb": spaces.Box(0, 255, (4, 4, 3), np.uint8), "depth": spaces.Box(0, np.inf, (4, 4, 1), np.float32),
            "lidar": spaces.Box(0, np.inf, (360,), np.float32),
            "radio": spaces.Box(0, 255, (RADIO_SLOTS * SIGNED_BYTES,), np.uint8),
            "radio_times": spaces.Box(0, np.inf, (RADIO_SLOTS,), np.float64)})
        self.action_space = spaces.Box(-1, 1, (2,), np.float32)
        # The world's radio as the attacks reach it: its rate, and the fleet an insider is handed a key of.
        self.radio = SimpleNamespace(fleet=FleetKeys.draw(np.random.default_rng(0)), config=RadioConfig())

    def _obs(self):
        rows, times = np.zeros(RADIO_SLOTS * SIGNED_BYTES, np.uint8), np.zeros(RADIO_SLOTS)
        if self.k % 5 == 1:  # sent at the step before, 20 ms ago
            sent = (self.k - 1) * DT
            lead = Broadcast(1, 2.0 + 0.5 * sent, 0.0, 0.0, 0.5, 0.0, False)
            rows[:SIGNED_BYTES] = np.frombuffer(sign(V2VMessage(self.k // 5 + 1, sent, lead), TEST_FLEET.signing_key(1)), np.uint8)
            times[0] = self.k * DT
        return {"rgb": np.zeros((4, 4, 3), np.uint8), "depth": np.ones((4, 4, 1), np.float32),
                "lidar": np.ones(360, np.float32), "radio": rows, "radio_times": times}

    def _info(self):
        return {"time": self.k * DT, "pose": np.array([0.5 * self.k * DT, 0.0, 0.0]), "lead_x": 2.0, "lead_y": 0.0,
                "lead_yaw": 0.0, "sign_in_view": False,
                "sign_mask": np.zeros((4, 4), bool),
                "d_true": np.nan, "dist_to_stop_line": 5.0}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.k = 0
        return self._obs(), self._info()

    def step(self, action):
        self.k += 1
        return self._obs(), 0.0, False, False, self._info()


def _drive(name: str, params: dict, seconds: float = 4.0):
    """The receiver over ``seconds`` of the attacked radio (the attack from 1 s to 3 s)."""
    env = ATTACKS[name](RadioEnv(), start_s=1.0, duration_s=2.0, **params)
    obs, info = env.reset(seed=0)
    car, injected, speeds = BroadcastReceiver(TEST_FLEET.trust_store()), 0, []
    for _ in range(int(round(seconds / DT))):
        obs, _, _, _, info = env.step(np.zeros(2))
        injected += info.get("radio_injected", 0)
        speeds += [(info["time"], m.state.speed_mps, m.state.x_m) for m in car.hear(obs, info["time"])]
    return car, injected, speeds


def test_the_honest_radio_is_accepted_whole():
    car, injected, _ = _drive("radio_jam", {}, seconds=0.9)  # before the window opens
    assert injected == 0 and car.accepted == 9 and sum(car.refused.values()) == 0


@pytest.mark.parametrize("name,params,why", [("radio_forge", {}, "bad signature"),
                                                  ("radio_replay", {"age_s": 0.5}, "replayed")])
def test_every_forged_or_replayed_message_is_refused_and_the_leads_own_still_heard(name, params, why):
    car, injected, heard = _drive(name, params)
    assert injected >= 15 and car.refused[why] == injected and car.refused[why] == sum(car.refused.values())
    assert car.accepted == 40  # every genuine message, attack or not
    assert all(speed == 0.5 for _, speed, _ in heard)


def test_a_jammed_radio_is_silent_in_its_window_and_a_delayed_one_stale():
    car, _, heard = _drive("radio_jam", {})
    assert car.accepted == 20 and not any(1.0 <= t < 3.0 for t, _, _ in heard)
    car, injected, heard = _drive("radio_delay", {"delay_s": 0.5})
    assert injected == 0 and car.refused["stale"] >= 15 and not any(1.05 <= t < 3.0 for t, _, _ in heard)


def test_an_insiders_lie_is_accepted_it_is_the_leads_own_signed_word():
    car, injected, heard = _drive("radio_lie", {"faster_mps": 0.5, "bias_m": 1.0, "rate_mps": 0.5})
    assert injected == 0 and car.accepted == 40 and sum(car.refused.values()) == 0
    lied = [(t, v, x) for t, v, x in heard if 1.0 <= t < 3.0]
    assert lied and all(v == 1.0 for _, v, _ in lied)
    # Farther by the move grown at 0.5 m/s since 1 s, up to 1 m.
    assert all(x == pytest.approx(2.0 + 0.5 * (t - DT) + min(0.5 * (t - 1.0), 1.0), abs=0.02) for t, _, x in lied)


@pytest.mark.parametrize("name,params", [("radio_delay", {"delay_s": 0.0}), ("radio_replay", {"age_s": 31.0}),
                                         ("radio_forge", {"ahead_m": 11.0}), ("radio_lie", {"rate_mps": -1.0})])
def test_a_bad_parameter_names_itself(name, params):
    with pytest.raises(ValueError, match=next(iter(params))):
        ATTACKS[name].check_params(params)


def test_forged_messages_say_what_the_attacker_chose_come_only_with_the_leads_and_are_numbered_past_it():
    from racf.sim.radio.message import parse

    env = ATTACKS["radio_forge"](RadioEnv(), start_s=1.0, duration_s=2.0, ahead_m=2.0, faster_mps=1.0)
    env.reset(seed=0)
    forged = []
    for _ in range(200):
        obs, _, _, _, info = env.step(np.zeros(2))
        rows = np.asarray(obs["radio"]).reshape(-1, SIGNED_BYTES)
        said = [parse(r.tobytes()) for r in rows if r.any()]
        if info["radio_injected"]:
            assert len(said) == 2  # the forgery beside the lead's own message, never alone
            forged.append((said[0], said[1]))
    assert len(forged) == 20
    for fake, real in forged:
        assert fake.seq == real.seq + 1 and fake.state.x_m == pytest.approx(real.state.x_m + 2.0)
        assert fake.state.speed_mps == pytest.approx(1.5) and not fake.state.braking


def test_a_replay_puts_on_the_air_only_what_fits_and_counts_it():
    env = ATTACKS["radio_replay"](RadioEnv(), start_s=1.0, duration_s=2.0, age_s=0.5)
    env.reset(seed=0)
    counted = sent = 0
    for _ in range(200):
        obs, _, _, _, info = env.step(np.zeros(2))
        counted += info["radio_injected"]
        sent += int(np.count_nonzero(np.asarray(obs["radio_times"]) > 0))
    assert counted == 20 and sent == 40 + 20  # the lead's forty, and each of twenty sent again once


def test_an_insiders_whole_lie_at_once_and_a_speed_never_below_zero():
    car, _, heard = _drive("radio_lie", {"faster_mps": -5.0, "bias_m": 1.0})
    lied = [(t, v, x) for t, v, x in heard if 1.0 <= t < 3.0]
    assert all(v == 0.0 for _, v, _ in lied)
    assert all(x == pytest.approx(2.0 + 0.5 * (t - DT) + 1.0, abs=0.02) for t, _, x in lied)


@pytest.mark.parametrize("name,param,edge,beyond", [
    ("radio_delay", "delay_s", 10.0, 10.01), ("radio_replay", "age_s", 30.0, 30.01),
    ("radio_forge", "ahead_m", -10.0, -10.01), ("radio_forge", "faster_mps", 10.0, 10.01),
    ("radio_lie", "faster_mps", 5.0, 5.01), ("radio_lie", "bias_m", -10.0, -10.01), ("radio_lie", "rate_mps", 10.0, 10.01)])
def test_each_parameter_takes_its_edge_and_refuses_past_it_or_a_flag(name, param, edge, beyond):
    ATTACKS[name].check_params({param: edge})
    for bad in (beyond, True):
        with pytest.raises(ValueError, match=param):
            ATTACKS[name].check_params({param: bad})


def test_a_stolen_key_says_its_vehicle_stands_just_ahead_at_the_radio_s_rate_and_is_taken():
    """Vehicle 5's key handed to the thief: from 1 s to 3 s, one message each 0.1 s (the radio's 10 Hz),
    numbered 1, 2, 3, ..., vehicle 5 standing (braking) 0.6 m ahead of the car's front: the car, at
    0.5 m/s from x 0, has its origin at 0.5 t, so vehicle 5's origin is at 0.5 t + 0.425 + 0.6."""
    env = ATTACKS["radio_stolen_key"](RadioEnv(), start_s=1.0, duration_s=2.0, vehicle=5, ahead_m=0.6)
    obs, info = env.reset(seed=0)
    car, said = BroadcastReceiver(TEST_FLEET.trust_store()), []
    for _ in range(int(round(4.0 / DT))):
        obs, _, _, _, info = env.step(np.zeros(2))
        said += [(info["time"], m) for m in car.hear(obs, info["time"]) if m.state.sender == 5]
    assert env.unwrapped.radio.fleet.handed_over == [5]
    assert len(said) == 20 and [m.seq for _, m in said] == list(range(1, 21))
    for t, m in said:
        assert m.t_s == pytest.approx(t) and m.state.x_m == pytest.approx(0.5 * t + 1.025) and m.state.braking
        assert m.state.speed_mps == 0.0 and m.state.y_m == 0.0
    assert [round(t, 2) for t, _ in said[:3]] == [1.0, 1.1, 1.2]
    with pytest.raises(ValueError, match="vehicle must be one of the fleet's"):
        ATTACKS["radio_stolen_key"](RadioEnv(), vehicle=9)
    with pytest.raises(ValueError, match="ahead_m must be in"):
        ATTACKS["radio_stolen_key"](RadioEnv(), ahead_m=11.0)
