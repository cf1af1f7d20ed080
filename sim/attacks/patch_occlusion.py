"""``PatchOcclusion`` (``patch_occlusion``): a textured occluder pasted over part of the stop sign in the RGB image.

It is named for what it is: an occluder in the image, not an adversarial patch. It hides
the sign's red pixels with a naturalistic texture; nothing about it is optimised against a
detector, and it exists in the image, not in the world (every view is the same paste). The
sticker printed on the sign in the scene, optimised against the learned detector, is
``physical_patch``.
"""

from __future__ import annotations

from typing import Any

import cv2
import gymnasium as gym
import numpy as np

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule, as_range
from racf.sim.world.patch_texture import natural_texture

__all__ = ["PatchOcclusion", "patch_rows", "paste_occluder"]


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


def paste_occluder(rgb: np.ndarray, region: np.ndarray, rho: float, texture: np.ndarray) -> np.ndarray:
    """``rgb`` (a copy) with ``texture`` stretched over the box of ``region`` (the sign's pixels)
    and shown on its top rows that hold a share ``rho`` of them."""
    covered = patch_rows(region, rho)
    if not covered.any():
        return rgb
    # Stretch the texture over the sign's box so it moves and scales with the sign.
    rows, cols = np.flatnonzero(region.any(axis=1)), np.flatnonzero(region.any(axis=0))
    y0, y1, x0, x1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    tex = cv2.resize(texture, (int(x1 - x0), int(y1 - y0)), interpolation=cv2.INTER_LINEAR)
    out = rgb.copy()
    box = covered[y0:y1, x0:x1]
    out[y0:y1, x0:x1][box] = tex[box]
    return out


class PatchOcclusion(AttackWrapper):
    """Covers a share ``rho`` of the stop sign's image region with a naturalistic occluder.

    The paper's patch attack as an image-space stand-in: after a stable detection and when the sign enters
    the braking window (see :class:`~racf.sim.attacks.schedule.AttackSchedule`), the top rows of
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
        >>> from sim.attacks import PatchOcclusion
        >>> env = PatchOcclusion(gym.make("RACF/QCar2-v4", camera_width=160, camera_height=120), rho=1.0, duration_s=1.0)
        >>> obs, info = env.reset(seed=0, options={"sign": 2})
        >>> info["attack_active"]
        False
    """

    name = "patch_occlusion"
    #: It is drawn on a stop sign's face: a crate has none.
    targets = ("sign", "drive")
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
        obs["rgb"] = paste_occluder(obs["rgb"], self.sign_region(info), self.rho, self._texture)
        return obs
