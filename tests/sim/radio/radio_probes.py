"""The radio's probes of issue 79 in a closed loop, the lead broadcasting (its profile cruise, 5 seeds each):

- **derived key**: messages from "vehicle 5" 0.6 m ahead of the car, signed with the key the fleet once
  derived from the public name "racf-fleet/vehicle-5" (on the old code 80 of 80 were taken);
- **locking, derived key**: one message from vehicle 1 numbered 2^32 - 1, on the next lane, signed with
  the key once derived from its name (on the old code it was taken, and the lead's next 46 refused);
- **locking, stolen key**: the same message signed with vehicle 1's own key (an insider's): what the
  anti-replay window has to stop.

Prints one JSON object (per probe: the attacker's messages, those taken, the lead's own refused):

    python -m tests.sim.radio.radio_probes > radio-probes.json
"""

from __future__ import annotations

import hashlib
import json
import math
import sys

import numpy as np
from nacl.signing import SigningKey

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.episode.stack import default_env
from racf.sim.attacks.broadcast import _put, _rows
from racf.sim.radio import Broadcast, V2VMessage, sign
from racf.vehicle import QCAR2_BOX_M

import gymnasium as gym

SEEDS = range(5)


def _derived(sender: int) -> SigningKey:
    """The key the fleet once made from vehicle ``sender``'s public name."""
    return SigningKey(hashlib.sha256(f"racf-fleet/vehicle-{sender}".encode()).digest())


class _Probe(gym.Wrapper):
    """Puts the probe's messages on the car's radio; counts them in ``info["radio_injected"]``."""

    def __init__(self, env, kind: str) -> None:
        super().__init__(env)
        self.kind = kind

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self._seq, self._next, self._locked = 0, 0.0, False
        self._key = (_derived(5) if self.kind == "derived key" else _derived(1) if self.kind == "locking, derived key"
                     else self.env.unwrapped.radio.fleet.hand_over(1))
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        now, (x, y, yaw) = float(info["time"]), (float(v) for v in info["pose"])
        sent = []
        if self.kind == "derived key" and now + 1e-9 >= self._next:
            self._next, self._seq = now + 0.1, self._seq + 1
            ahead = QCAR2_BOX_M[0] + 0.6
            said = Broadcast(5, x + ahead * math.cos(yaw), y + ahead * math.sin(yaw), yaw, 0.0, 0.0, True)
            sent.append(sign(V2VMessage(self._seq, now, said), self._key))
        elif self.kind.startswith("locking") and not self._locked and now >= 2.0:
            self._locked = True  # vehicle 1 on the next lane, numbered as high as a number goes
            said = Broadcast(1, x - 0.5 * math.sin(yaw), y + 0.5 * math.cos(yaw), yaw, 0.0, 0.0, False)
            sent.append(sign(V2VMessage(2 ** 32 - 1, now, said), self._key))
        if sent:
            obs = _put(dict(obs), [(now, raw) for raw in sent] + _rows(obs))
            info = {**info, "radio_injected": int(info.get("radio_injected", 0)) + len(sent)}
        return obs, reward, terminated, truncated, info


def main() -> int:
    out = {}
    for kind in ("derived key", "locking, derived key", "locking, stolen key"):
        rows = []
        for seed in SEEDS:
            spec = TrialSpec("clean", 1, 1.0, seed, target="lead_vehicle",
                             scenario_params={"profile": "cruise", "broadcast": "on"})
            result, log = run_trial(spec, make_env=lambda s, kind=kind: _Probe(default_env(s), kind))
            row = result.to_dict()
            rows.append({"seed": seed, "injected": int(log["radio_injected"].sum()),
                         "foreign_accepted": row["bc_foreign_accepted"], "genuine_refused": row["bc_genuine_refused"],
                         "episode_s": float(log["t"].iloc[-1]), "steps_at_rest": int((np.abs(log["speed"]) < 0.05).sum())})
        out[kind] = {"episodes": rows, "injected": sum(r["injected"] for r in rows),
                     "foreign_accepted": sum(r["foreign_accepted"] for r in rows),
                     "genuine_refused": sum(r["genuine_refused"] for r in rows)}
        print(kind, json.dumps({k: v for k, v in out[kind].items() if k != "episodes"}), file=sys.stderr)
    print(json.dumps({"probes": out, "seeds": list(SEEDS), "profile": "cruise"}, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
