"""One closed-loop episode: spec (what to run), plan (pure: spec + map -> reset options, the car's
mission and calibration), car (the car's software: it sees observations and the map), referee
(ground truth), stack (perception + estimator + brakers), record (the step log's one
declaration), runner (the one step loop) and scoring (pure: per-step log -> outcome). Batches
of episodes run in :mod:`racf.experiments.sweeps`."""

import lazy_loader

# Each name is imported on first use (SPEC 1): importing the package costs nothing, so the
# command line's help never waits for torch or scikit-learn.
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "plan": ["EpisodePlan", "plan_episode", "reset_options"],
    "record": ["STEP_COLUMNS", "STEP_LOG"],
    "runner": ["TrialResult", "run_trial"],
    "scoring": ["TargetOutcome", "score_log", "score_target"],
    "spec": ["DRIVE_S", "STRONG_RHO", "STRONG_T_ATK_S", "TABLE_SETTINGS", "TrialSpec", "parse_setting", "setting_name"],
    "stack": ["default_env"],
})
