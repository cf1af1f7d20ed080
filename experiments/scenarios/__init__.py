"""Scenarios: the situations episodes put the car in, as plug-ins (``racf.scenarios``).

:class:`Scenario` and :class:`Param` are what a user's scenario is made of; racf's own
(:mod:`~racf.experiments.scenarios.builtin`) register the same way. ``racf.plugins.SCENARIOS``
holds them by name.
"""

from racf.experiments.scenarios.base import TARGET_KINDS, Param, Scenario
from racf.sim.world.manager import WorldManager

__all__ = ["Param", "Scenario", "TARGET_KINDS", "WorldManager"]
