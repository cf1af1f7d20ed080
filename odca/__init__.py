"""ODCA: alignment, the kinematic branch, the voting gate, temporal prior, delta head, losses,
training and the online module.

Knows nothing of the simulator: it sees distance series and the car's odometry, as the
paper's offline benchmark does.
"""

import lazy_loader

# Each name is imported on first use (SPEC 1): importing the package costs nothing, so the
# command line's help never waits for torch or scikit-learn.
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "align": ["Alignment", "fit_alignment"],
    "gate": ["SOURCES", "GateConfig", "vote"],
    "kinematics": ["KinematicBranch", "KinematicsConfig"],
    "online": ["ODCA", "FusedSample", "ODCAConfig"],
    "prior": ["CheckpointError", "Chronos2Prior", "LastValuePrior", "TemporalPrior"],
})
