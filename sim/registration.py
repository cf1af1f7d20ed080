"""One idempotent registration of the racf envs with Gymnasium."""

import gymnasium as gym

__all__ = ["ENV_ID", "register_envs"]

#: Bump the version when dynamics, reward or spaces change. v1: depth is (H, W, 1), not (H, W).
#: v2: the localiser's fix (``gps``) and the sensors' timestamps; the state as the encoder and
#: the IMU measure it. v3: sensor profiles (the swept A2M12 through Quanser's driver and the
#: camera at 30 Hz by default) and ``lidar_beam_times``. v4: the radio (``radio``, ``radio_times``: what the
#: world's vehicles broadcast, signed). Only the newest version is registered: asking for an older one
#: fails with Gymnasium's error, which names this one.
ENV_ID = "RACF/QCar2-v4"


def register_envs() -> None:
    """Registers ``RACF/QCar2-v4``; calling it again does nothing."""
    if ENV_ID in gym.registry:
        return
    gym.register(id=ENV_ID, entry_point="racf.sim.env.qcar2_env:QCar2Env", max_episode_steps=None,
                 disable_env_checker=False)
