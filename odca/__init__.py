"""ODCA: alignment, the kinematic branch, the voting gate, temporal prior, delta head, losses,
training and the online module.

Knows nothing of the simulator: it sees distance series and the car's odometry, as the
paper's offline benchmark does.
"""

from racf.odca.align import Alignment, fit_alignment
from racf.odca.gate import SOURCES, GateConfig, vote
from racf.odca.kinematics import KinematicBranch, KinematicsConfig
from racf.odca.online import ODCA, FusedSample, ODCAConfig
from racf.odca.prior import CheckpointError, Chronos2Prior, LastValuePrior, TemporalPrior

__all__ = ["ODCA", "ODCAConfig", "FusedSample", "Alignment", "fit_alignment", "GateConfig", "vote", "SOURCES",
           "KinematicsConfig", "KinematicBranch", "TemporalPrior", "Chronos2Prior", "LastValuePrior",
           "CheckpointError"]
