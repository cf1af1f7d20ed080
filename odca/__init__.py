"""ODCA: alignment, the kinematic branch, the voting gate, temporal prior, delta head, losses,
training and the online module.

Knows nothing of the simulator: it sees distance series and the car's odometry, as the
paper's offline benchmark does.
"""

from typing import TYPE_CHECKING

import lazy_loader

# Each name is imported on first use (SPEC 1), as __init__.pyi lists them: importing the package costs
# nothing, so the command line's help never waits for torch, scikit-learn or the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

if TYPE_CHECKING:  # the same names for editors that read no stub (jedi); a test holds the two lists equal
    from .align import Alignment, fit_alignment
    from .gate import SOURCES, GateConfig, vote
    from .kinematics import KinematicBranch, KinematicsConfig
    from .online import ODCA, FusedSample, ODCAConfig
    from .prior import CheckpointError, Chronos2Prior, LastValuePrior, TemporalPrior
