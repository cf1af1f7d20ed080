"""Perception and control that see observations only (no simulator imports)."""

from controllers.lane_follower import StanleyConfig, StanleyController

__all__ = ["StanleyConfig", "StanleyController"]
