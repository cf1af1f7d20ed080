"""racf's own scenarios, registered the way a user's are (``racf.scenarios`` entry points):
the approach to a stop sign, the approach to a crate and a drive past several targets. Other
situations have packages of their own (``racf.experiments.scenarios.cross_traffic``,
``racf.experiments.scenarios.stale_map``)."""

from __future__ import annotations

from racf.experiments.scenarios.base import Scenario

__all__ = ["SignApproach", "ObstacleApproach", "Drive"]


class SignApproach(Scenario):
    name = "sign"
    meaning = "approach one of the map's four stop signs and stop at its line"
    target = "sign"


class ObstacleApproach(Scenario):
    name = "obstacle"
    meaning = "approach one of the two crates standing in the lane and stop before it"
    target = "obstacle"


class Drive(Scenario):
    name = "drive"
    meaning = "a random route drawn from the seed that meets two or more stop signs or crates"
    target = "drive"
