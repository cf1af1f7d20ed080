"""The Gymnasium env of the QCar 2 on the indoor map."""

from racf.sim.env.config import EnvConfig
from racf.sim.env.qcar2_env import QCar2Env

__all__ = ["EnvConfig", "QCar2Env"]
