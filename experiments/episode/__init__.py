"""One closed-loop episode: spec (what to run), plan (pure: spec + map -> reset options, the car's
mission and calibration), car (the car's software: it sees observations and the map), referee
(ground truth), stack (perception + estimator + brakers), record (the step log's one
declaration), runner (the one step loop) and scoring (pure: per-step log -> outcome). Batches
of episodes run in :mod:`racf.experiments.sweeps`."""

from racf.experiments.car.estimators import ESTIMATORS, make_estimator
from racf.experiments.episode.plan import EpisodePlan, plan_episode, reset_options
from racf.experiments.episode.record import STEP_COLUMNS, STEP_LOG
from racf.experiments.episode.runner import TrialResult, run_trial
from racf.experiments.episode.scoring import TargetOutcome, score_log, score_target
from racf.experiments.episode.spec import (DRIVE_S, STRONG_RHO, STRONG_T_ATK_S, TABLE_SETTINGS, TrialSpec, parse_setting,
                                      setting_name)
from racf.experiments.episode.stack import default_env

__all__ = ["DRIVE_S", "EpisodePlan", "STEP_COLUMNS", "STEP_LOG", "plan_episode", "ESTIMATORS", "STRONG_RHO", "STRONG_T_ATK_S", "TABLE_SETTINGS", "TargetOutcome", "TrialResult",
           "TrialSpec", "default_env", "make_estimator", "parse_setting", "reset_options", "run_trial", "score_log",
           "score_target", "setting_name"]
