"""ODCA: alignment, gate, temporal prior, delta head, losses, training and the online module.

Knows nothing of the simulator: it sees distance series, as the paper's offline benchmark does.
"""

from odca.align import Alignment, fit_alignment
from odca.gate import GateConfig, fuse, gate_weight
from odca.online import ODCA, FusedSample, ODCAConfig
from odca.prior import CheckpointError, Chronos2Prior, LastValuePrior, TemporalPrior

__all__ = ["ODCA", "ODCAConfig", "FusedSample", "Alignment", "fit_alignment", "GateConfig", "gate_weight", "fuse",
           "TemporalPrior", "Chronos2Prior", "LastValuePrior", "CheckpointError"]
