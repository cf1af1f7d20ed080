"""Following the car ahead, as one car stage: its perception, defence instance, policy, step-log
columns and drawing (:mod:`.stage`)."""
