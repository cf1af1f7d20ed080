"""One closed-loop episode: spec (what to run), plan (pure: spec + map -> reset options, the car's
mission and calibration), car (the car's software: it sees observations and the map), referee
(ground truth), stack (perception + estimator + brakers), record (the step log's one
declaration), runner (the one step loop) and scoring (pure: per-step log -> outcome). Batches
of episodes run in :mod:`racf.experiments.sweeps`."""

from typing import TYPE_CHECKING

import lazy_loader

# Each name is imported on first use (SPEC 1), as __init__.pyi lists them: importing the package costs
# nothing, so the command line's help never waits for torch, scikit-learn or the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

if TYPE_CHECKING:  # the same names for editors that read no stub (jedi); a test holds the two lists equal
    from .plan import EpisodePlan, plan_episode, reset_options
    from .record import STEP_COLUMNS, STEP_LOG
    from .runner import TrialResult, run_trial
    from .scoring import TargetOutcome, score_log, score_target
    from .spec import DRIVE_S, STRONG_RHO, STRONG_T_ATK_S, TABLE_SETTINGS, TrialSpec, parse_setting, setting_name
    from .stack import default_env
