"""One idempotent registration of the racf envs with Gymnasium."""

import gymnasium as gym

__all__ = ["ENV_ID", "register_envs"]

#: Bump the version when dynamics, reward or spaces change. v1: depth is (H, W, 1), not (H, W).
ENV_ID = "RACF/QCar2-v1"


def register_envs() -> None:
    """Registers ``RACF/QCar2-v1``; calling it again does nothing."""
    if ENV_ID in gym.registry:
        return
    gym.register(id=ENV_ID, entry_point="sim.env.qcar2_env:QCar2Env", max_episode_steps=None,
                 disable_env_checker=False)
