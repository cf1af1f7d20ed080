"""racf simulator: the Quanser QCar 2 and its indoor map in MuJoCo, as a Gymnasium env.

Importing ``sim`` registers ``RACF/QCar2-v4`` (so ``gym.make("racf.sim:RACF/QCar2-v4")`` works in
a fresh process) and selects headless EGL rendering unless ``MUJOCO_GL`` is already set.
"""

from racf.sim._gl import ensure_gl_backend

ensure_gl_backend()

from racf.sim.registration import ENV_ID, register_envs  # noqa: E402

register_envs()

__all__ = ["ENV_ID", "register_envs"]
