"""``StealthRamp``: a depth bias that grows as fast as the defence lets it, and no faster."""

from __future__ import annotations

import inspect
import math
from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim.attacks._common import check_region
from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule

__all__ = ["StealthRamp", "quiet_bias", "takes_keyword"]

#: Bisection steps of the search for the largest quiet bias (2^-12 of the wanted step).
_SEARCH_STEPS = 12


def takes_keyword(function, name: str) -> bool:
    """Whether ``function`` accepts the keyword argument ``name`` (by name or through ``**kwargs``)."""
    try:
        parameters = inspect.signature(function).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == name or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters)


def quiet_bias(would_pass, current: float, wanted: float, steps: int = _SEARCH_STEPS) -> float:
    """The bias nearest ``wanted``, between ``current`` and ``wanted``, for which
    ``would_pass(bias)`` holds (bisection: the quiet set is taken as an interval around the
    truth); ``current`` when even a step towards ``wanted`` fails."""
    if would_pass(wanted):
        return wanted
    lo, hi = current, wanted
    if not would_pass(lo):
        return current
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if would_pass(mid) else (lo, mid)
    return lo


class StealthRamp(AttackWrapper):
    """Adds a bias to the sign's depth that grows at ``rate_mps``, as far as the defence's own
    detector lets it without flagging a step.

    White box: it is handed the defence (``attach_defence``: the runner gives it the car's
    estimator) and, before each step, asks it ``would_pass(depth=...)`` for the depth it
    plans (the true depth plus the bias, with the bias scaled by ``1 / margin`` to keep a
    reserve for the camera's noise), with the car's odometry. It takes the largest bias,
    no further than ``rate_mps`` allows, that the defence would not flag, so the gate (or
    innovation test) stays quiet. Against a defence with no detector (raw depth), or none
    attached, the ramp is limited by ``rate_mps`` alone.

    Args:
        env: the racf env.
        rate_mps: how fast the bias may grow, m/s (0 to 20).
        direction: ``+1`` (farther: the dangerous case) or ``-1``.
        margin: the share of the defence's room it uses (0 to 1].
        region: ``"sign"`` or ``"frame"``.
        **schedule: ``AttackSchedule`` fields; its defaults are the protocol's.
    """

    name = "stealth_ramp"
    threat_model = "white box"
    #: The LiDAR moves with the depth (``FrustumSpoof``): the defence is asked with the shift.
    moves_lidar = False
    #: The sign's image is scaled with the depth (``FrustumSpoof(scale_box=True)``): a defence
    #: whose ``would_pass`` takes ``size_shift`` (it has a size witness) is asked with the size
    #: moved too; one that does not take it has nothing the scaling moves.
    moves_size = False

    def __init__(self, env: gym.Env, rate_mps: float = 1.0, direction: int = 1, margin: float = 0.9,
                 region: str = "sign", **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, rate_mps=rate_mps, direction=direction, margin=margin,
                                                 region=region, **schedule)
        if not (isinstance(rate_mps, (int, float)) and 0.0 <= rate_mps <= 20.0):
            raise ValueError(f"rate_mps must be a number of m/s in [0, 20], got {rate_mps!r}")
        if direction not in (-1, 1):
            raise ValueError(f"direction must be -1 or 1, got {direction!r}")
        if not (isinstance(margin, (int, float)) and 0.0 < margin <= 1.0):
            raise ValueError(f"margin must be in (0, 1], got {margin!r}")
        self.rate_mps, self.direction, self.margin = float(rate_mps), int(direction), float(margin)
        self.region = check_region(region)
        super().__init__(env, AttackSchedule(**schedule))
        self.bias = 0.0
        self.held_back = 0  # steps the defence's room, not the rate, limited the bias
        self._last_time: float | None = None
        self._asks_size: bool | None = None  # whether the defence is asked with size_shift (read once)

    def _on_reset(self) -> None:
        self.bias = 0.0
        self.held_back = 0
        self._last_time = None
        self._asks_size = None

    def attach_defence(self, defence) -> None:
        super().attach_defence(defence)
        self._asks_size = None  # a new defence: read its signature afresh

    def _next_bias(self, obs: dict, info: dict, dt: float) -> float:
        wanted = self.bias + self.direction * self.rate_mps * dt
        probe = getattr(self.defence, "would_pass", None)
        d_true = float(info.get("d_true", math.nan))
        if probe is None or not math.isfinite(d_true) or dt <= 0:
            return wanted
        state = np.asarray(obs["state"], float)
        speed, yaw_rate = float(state[0]), float(state[2])
        old = self.bias

        if self._asks_size is None:  # the defence's signature, read once an episode, not per step
            self._asks_size = self.moves_size and takes_keyword(probe, "size_shift")
        asks_size = self._asks_size

        def quiet(bias: float) -> bool:
            reserve = bias / self.margin
            extra = {"size_shift": reserve - old} if asks_size else {}
            return bool(probe(depth=d_true + reserve, speed_mps=speed, dt=dt, yaw_rate_radps=yaw_rate,
                              lidar_shift=(reserve - old) if self.moves_lidar else 0.0, **extra))

        bias = quiet_bias(quiet, old, wanted)
        self.held_back += int(bias != wanted)
        return bias

    def _attack(self, obs: dict, info: dict) -> dict:
        t = float(info["time"])
        dt = t - self._last_time if self._last_time is not None else 0.0
        self._last_time = t
        self.bias = self._next_bias(obs, info, dt)
        depth = obs["depth"].copy()
        plane = depth[..., 0]
        where = (plane > 0) & (self.sign_region(info, 1) if self.region == "sign" else True)
        shifted = plane[where] + self.bias
        plane[where] = np.where(shifted > 0, shifted, 0.0).astype(depth.dtype)
        obs["depth"] = depth
        return obs
