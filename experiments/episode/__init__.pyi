# The package's names, for type checkers and editors, and for lazy_loader, which imports each on
# first use (racf's __init__.py reads this file): the one list of what the package exports.
from .plan import EpisodePlan, plan_episode, reset_options
from .record import STEP_COLUMNS, STEP_LOG
from .runner import TrialResult, run_trial
from .scoring import TargetOutcome, score_log, score_target
from .spec import DRIVE_S, STRONG_RHO, STRONG_T_ATK_S, TABLE_SETTINGS, TrialSpec, parse_setting, setting_name
from .stack import default_env

__all__ = ["DRIVE_S", "EpisodePlan", "STEP_COLUMNS", "STEP_LOG", "plan_episode", "STRONG_RHO", "STRONG_T_ATK_S", "TABLE_SETTINGS", "TargetOutcome", "TrialResult",
           "TrialSpec", "default_env", "parse_setting", "reset_options", "run_trial", "score_log",
           "score_target", "setting_name"]
