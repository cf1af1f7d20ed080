"""The Gymnasium env of the QCar 2 on the indoor map."""

from typing import TYPE_CHECKING

import lazy_loader

# Each name is imported on first use (SPEC 1), as __init__.pyi lists them: importing the package costs
# nothing, so the command line's help never waits for torch, scikit-learn or the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

if TYPE_CHECKING:  # the same names for editors that read no stub (jedi); a test holds the two lists equal
    from .config import EnvConfig
    from .qcar2_env import QCar2Env
