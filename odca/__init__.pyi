# The package's names, for type checkers and editors, and for lazy_loader, which imports each on
# first use (racf's __init__.py reads this file): the one list of what the package exports.
from .align import Alignment, fit_alignment
from .gate import SOURCES, GateConfig, vote
from .kinematics import KinematicBranch, KinematicsConfig
from .online import ODCA, FusedSample, ODCAConfig
from .prior import CheckpointError, Chronos2Prior, LastValuePrior, TemporalPrior

__all__ = ["ODCA", "ODCAConfig", "FusedSample", "Alignment", "fit_alignment", "GateConfig", "vote", "SOURCES",
           "KinematicsConfig", "KinematicBranch", "TemporalPrior", "Chronos2Prior", "LastValuePrior",
           "CheckpointError"]
