"""``PatchAttack``: a textured patch over part of the stop sign in the RGB image."""

from __future__ import annotations

from typing import Any

import cv2
import gymnasium as gym
import numpy as np

from sim.attacks.base import AttackWrapper
from sim.attacks.schedule import AttackSchedule, as_range
from sim.attacks.texture import natural_texture

__all__ = ["PatchAttack", "patch_rows"]


def patch_rows(mask: np.ndarray, rho: float) -> np.ndarray:
    """(H, W) bool: the top rows of ``mask`` whose pixels come nearest to a share ``rho`` of it.

    The covered share is within one pixel row of ``rho`` (the cut falls on a row boundary).
    """
    covered = np.zeros_like(mask, dtype=bool)
    rows = np.nonzero(mask.any(axis=1))[0]
    if rows.size == 0 or rho <= 0:
        return covered
    counts = mask[rows].sum(axis=1)
    cumulative = np.concatenate([[0], np.cumsum(counts)])
    k = int(np.argmin(np.abs(cumulative - rho * cumulative[-1])))
    covered[rows[:k]] = mask[rows[:k]]
    return covered


class PatchAttack(AttackWrapper):
    """Covers a share ``rho`` of the stop sign's image region with a naturalistic patch.

    The paper's physical patch attack: after a stable detection and when the sign enters
    the braking window (see :class:`~sim.attacks.schedule.AttackSchedule`), the top rows of
    the sign's face holding a share ``rho`` of its pixels show a textured patch for
    ``T_atk ~ U(0.5, 3.0)`` s, then a cooldown. The patch lies on the sign's face, so the
    depth of its pixels is the face's depth: the depth image is left as it is.

    Args:
        env: the racf env (or a wrapper of it).
        rho: covered share, a value or a (low, high) range drawn once per episode, in [0, 1].
        **schedule: ``AttackSchedule`` fields; ``duration_s`` is ``T_atk`` (a value or a
            (low, high) range, default U(0.5, 3.0) s); cooldown_s, window_s, stable_steps, trigger.

    Example:
        >>> import gymnasium as gym, sim
        >>> from sim.attacks import PatchAttack
        >>> env = PatchAttack(gym.make("RACF/QCar2-v3", camera_width=160, camera_height=120), rho=1.0, duration_s=1.0)
        >>> obs, info = env.reset(seed=0, options={"sign": 2})
        >>> info["attack_active"]
        False
    """

    name = "patch"
    episode_params = ("rho",)

    def __init__(self, env: gym.Env, rho: Any = (0.9, 1.0), **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, rho=rho, **schedule)
        self.rho_range = as_range("rho", rho, 0.0, 1.0)
        super().__init__(env, AttackSchedule(**schedule))
        self.rho = self.rho_range[0]
        self._texture = np.zeros((64, 64, 3), np.uint8)

    def _on_reset(self) -> None:
        self.rho = float(self.rng.uniform(*self.rho_range))
        self._texture = natural_texture(self.rng)

    def _attack(self, obs: dict, info: dict) -> dict:
        region = self.sign_region(info)
        covered = patch_rows(region, self.rho)
        if not covered.any():
            return obs
        # Stretch the texture over the sign's box so it moves and scales with the sign.
        rows, cols = np.nonzero(region)
        y0, y1, x0, x1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
        tex = cv2.resize(self._texture, (int(x1 - x0), int(y1 - y0)), interpolation=cv2.INTER_LINEAR)
        rgb = obs["rgb"].copy()
        box = covered[y0:y1, x0:x1]
        rgb[y0:y1, x0:x1][box] = tex[box]
        obs["rgb"] = rgb
        return obs
