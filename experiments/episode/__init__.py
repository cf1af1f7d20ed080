"""One closed-loop episode: spec (what to run), car (the map and camera knowledge the car is
given), stack (perception + estimator + brakers), runner (the one step loop) and scoring
(pure: per-step log -> outcome). Batches of episodes run in :mod:`racf.experiments.sweeps`."""

from racf.experiments.episode.estimators import ESTIMATORS, make_estimator
from racf.experiments.episode.runner import TrialResult, reset_options, run_trial
from racf.experiments.episode.scoring import TargetOutcome, score_log, score_target
from racf.experiments.episode.spec import (DRIVE_S, STRONG_RHO, STRONG_T_ATK_S, TABLE_SETTINGS, TrialSpec, parse_setting,
                                      setting_name)
from racf.experiments.episode.stack import default_env

__all__ = ["DRIVE_S", "ESTIMATORS", "STRONG_RHO", "STRONG_T_ATK_S", "TABLE_SETTINGS", "TargetOutcome", "TrialResult",
           "TrialSpec", "default_env", "make_estimator", "parse_setting", "reset_options", "run_trial", "score_log",
           "score_target", "setting_name"]
