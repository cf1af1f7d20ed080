"""When an attack is on: the paper's protocol, as a small state machine.

The attacker knows where the sign is (it reads the simulator's ground truth, as the
paper's threat model allows). An attack window opens once the sign has been visible for
``stable_steps`` consecutive steps (the controller has a stable detection) and the sign
is inside the braking window: the car would reach the stop line within ``window_s`` at
its current speed. The window lasts a duration drawn from ``duration_s`` (a fixed value or
a (low, high) uniform range), then a cooldown of ``cooldown_s`` follows before the next
window may open. ``trigger="always"`` opens the first window at the first step instead, and
``trigger="at_time"`` at the first step at or after ``start_s`` seconds into the episode.

An experiment sets these per attack (``TrialSpec.attack_params``, ``--attack-param``, a
sweep's ``[params.NAME]``) by the names in :data:`SCHEDULE_PARAMS`; ``duration_s`` is the
episode's ``t_atk`` and ``stable_steps`` its ``stable_steps``.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["AttackSchedule", "as_range", "TRIGGERS", "SCHEDULE_PARAMS"]

TRIGGERS = ("braking_window", "always", "at_time")
#: The schedule's fields an experiment may set per attack (the others come from the episode).
SCHEDULE_PARAMS = ("trigger", "start_s", "window_s", "cooldown_s", "max_windows", "min_sign_px")


def as_range(name: str, value: Any, lo: float, hi: float) -> tuple[float, float]:
    """A fixed value or a (low, high) pair inside [lo, hi], as a (low, high) pair; ValueError otherwise."""
    pair = (value, value) if isinstance(value, numbers.Real) and not isinstance(value, bool) else value
    try:
        a, b = (float(v) for v in pair)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or a (low, high) pair in [{lo}, {hi}], got {value!r}") from None
    if not (lo <= a <= b <= hi):
        raise ValueError(f"{name} must lie in [{lo}, {hi}] with low <= high, got {value!r}")
    return a, b


@dataclass
class AttackSchedule:
    """Decides, step by step, whether an attack is active.

    Attributes:
        duration_s: window length, seconds: a value or a (low, high) uniform range.
        cooldown_s: quiet time after a window, seconds.
        window_s: the braking window, as time to the stop line at the current speed.
        stable_steps: consecutive steps with the sign visible before an attack may start.
        min_sign_px: ground-truth mask pixels that count as visible.
        trigger: ``"braking_window"`` (the protocol), ``"always"`` (from the first step) or
            ``"at_time"`` (from ``start_s``).
        start_s: with ``trigger="at_time"``: when the first window opens, s into the episode, in
            [0, 120].
        max_windows: most windows per episode.
    """

    duration_s: Any = (0.5, 3.0)
    cooldown_s: float = 2.0
    window_s: float = 1.0
    stable_steps: int = 3
    min_sign_px: int = 12
    trigger: str = "braking_window"
    max_windows: int = 1
    start_s: float = 0.0
    windows: list[tuple[float, float]] = field(default_factory=list, init=False)

    def __post_init__(self) -> None:
        self.duration_s = as_range("duration_s", self.duration_s, 0.0, 60.0)
        for name, lo, hi in (("cooldown_s", 0.0, 60.0), ("window_s", 0.0, 60.0), ("start_s", 0.0, 120.0)):
            value = getattr(self, name)
            if not (isinstance(value, numbers.Real) and not isinstance(value, bool) and lo <= value <= hi):
                raise ValueError(f"{name} must be in [{lo}, {hi}] s, got {value!r}")
        for name in ("stable_steps", "min_sign_px", "max_windows"):
            value = getattr(self, name)
            if not (isinstance(value, numbers.Integral) and value >= 0):
                raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
        if self.trigger not in TRIGGERS:
            raise ValueError(f"trigger must be one of {TRIGGERS}, got {self.trigger!r}")
        if self.start_s and self.trigger != "at_time":
            raise ValueError(f"start_s applies to trigger 'at_time', not {self.trigger!r}")
        self.reset(np.random.default_rng(0))

    def reset(self, rng: np.random.Generator) -> None:
        self._rng = rng
        self._visible = 0
        self._end = -np.inf
        self._quiet_until = -np.inf
        self.windows = []

    def update(self, info: dict) -> bool:
        """Whether the attack is active at the step ``info`` describes (call once per step, in order)."""
        t = float(info["time"])
        visible = int(np.count_nonzero(info["sign_mask"])) >= self.min_sign_px
        self._visible = self._visible + 1 if visible else 0
        if t < self._end - 1e-6:  # float times: a 0.2 s window is 10 steps at 50 Hz, not 11
            return True
        if len(self.windows) < self.max_windows and t >= self._quiet_until and self._should_open(info):
            duration = float(self._rng.uniform(*self.duration_s))
            self._end = t + duration
            self._quiet_until = self._end + self.cooldown_s
            self.windows.append((t, self._end))
            return duration > 0
        return False

    def _should_open(self, info: dict) -> bool:
        if self.trigger == "always":
            return True
        if self.trigger == "at_time":
            return float(info["time"]) >= self.start_s - 1e-6
        speed = max(float(info["speed"]), 1e-3)
        return self._visible >= self.stable_steps and 0.0 < float(info["dist_to_stop_line"]) <= self.window_s * speed
