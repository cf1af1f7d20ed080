# The package's names, for type checkers and editors, and for lazy_loader, which imports each on
# first use (racf's __init__.py reads this file): the one list of what the package exports.
from .config import EnvConfig
from .qcar2_env import QCar2Env

__all__ = ["EnvConfig", "QCar2Env"]
