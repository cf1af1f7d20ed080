"""Every batch of episodes, on one path: specs (grid / random), the result store (content-hashed
ids, parts written whole, resume), executors (in-process, a spawned pool or Ray), the one
summary and the report. Sweeps, ``racf trials`` and its table (``batches``), the attack study
(``studies``) and dataset collection all run through :func:`racf.experiments.sweeps.run.run_episodes`."""
