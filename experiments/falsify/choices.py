"""What a search can be asked for, in a module of its own: the command line offers the choices
without importing the search (Optuna, the episode code)."""

__all__ = ["SAMPLERS", "OBJECTIVES"]

#: The samplers: Optuna's TPE and CMA-ES (guided) and random search (the baseline).
SAMPLERS = ("tpe", "cmaes", "random")
#: What a search minimises: ``rule``, the stop rule's robustness; ``rule-undetected``, that minus
#: the attack's undetected error (the referee's largest |acted-on - true distance| before the
#: defence flagged it): a slope towards attacks the defence does not see, where the rule's
#: robustness alone is flat. Either way a violation is the rule's robustness below zero.
OBJECTIVES = ("rule", "rule-undetected", "gap")
