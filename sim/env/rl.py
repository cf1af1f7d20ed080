"""Wrappers for reinforcement-learning libraries (stable-baselines3, gymnasium's vector envs).

The env speaks SI units: the action is [speed m/s, steering rad] and depth is float32
metres, which is what controllers want. RL libraries prefer a [-1, 1] action box and
uint8 images; these wrappers give them that without touching the env:

    >>> import gymnasium as gym, sim
    >>> from sim.env.rl import rl_env
    >>> env = rl_env(camera_width=160, camera_height=120)   # RescaleAction + DepthAsImage
    >>> env.action_space.low, env.observation_space["depth"].dtype
    (array([-1., -1.], dtype=float32), dtype('uint8'))
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.wrappers import RescaleAction

__all__ = ["DepthAsImage", "FiniteLidar", "rl_env"]


class DepthAsImage(gym.ObservationWrapper):
    """Depth as a uint8 image: 0..max_depth_m mapped to 1..255, 0 = no return (as in the env).

    Args:
        env: an env whose observation has ``depth`` (H, W, 1) float32 metres.
        max_depth_m: depths beyond this saturate at 255.
    """

    def __init__(self, env: gym.Env, max_depth_m: float = 5.0) -> None:
        super().__init__(env)
        if not (isinstance(max_depth_m, (int, float)) and 0 < max_depth_m <= 100):
            raise ValueError(f"max_depth_m must be a number in (0, 100] m, got {max_depth_m!r}")
        space = env.observation_space
        if not isinstance(space, spaces.Dict) or "depth" not in space.spaces or len(space["depth"].shape) != 3:
            raise ValueError("DepthAsImage needs a Dict observation space with depth (H, W, 1)")
        self.max_depth_m = float(max_depth_m)
        self.observation_space = spaces.Dict({**space.spaces,
                                              "depth": spaces.Box(0, 255, space["depth"].shape, np.uint8)})

    def observation(self, observation: dict) -> dict:
        depth = observation["depth"]
        scaled = np.clip(np.rint(1 + depth * (254.0 / self.max_depth_m)), 1, 255)
        return {**observation, "depth": np.where(depth > 0, scaled, 0).astype(np.uint8)}


class FiniteLidar(gym.ObservationWrapper):
    """LiDAR ranges with no return as 0 (the A2M12 driver's own convention) instead of inf,
    which a network cannot take."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        space = env.observation_space
        if not isinstance(space, spaces.Dict) or "lidar" not in space.spaces:
            raise ValueError("FiniteLidar needs a Dict observation space with lidar")
        lidar = space["lidar"]
        high = np.float32(np.finfo(np.float32).max)
        self.observation_space = spaces.Dict({**space.spaces, "lidar": spaces.Box(0.0, high, lidar.shape, np.float32)})

    def observation(self, observation: dict) -> dict:
        lidar = observation["lidar"]
        return {**observation, "lidar": np.where(np.isfinite(lidar), lidar, 0.0).astype(np.float32)}


def rl_env(env_id: str | None = None, max_depth_m: float = 5.0, **kwargs) -> gym.Env:
    """``gym.make(env_id, **kwargs)`` with a [-1, 1] action box (``RescaleAction``), uint8 depth and
    finite LiDAR ranges (``FiniteLidar``)."""
    from racf.sim.registration import ENV_ID

    env = FiniteLidar(DepthAsImage(gym.make(env_id or ENV_ID, **kwargs), max_depth_m))
    one = np.ones(env.action_space.shape, np.float32)
    return RescaleAction(env, -one, one)
