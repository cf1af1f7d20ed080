"""The released batteries' names, for the command line's choices and help: ``battery.BATTERIES`` builds
the batteries themselves, whose rows import the episode code (seconds), which ``--help`` must not
wait for. A test holds the two equal."""

__all__ = ["BATTERY_NAMES", "DEFAULT_BATTERY"]

BATTERY_NAMES = ("racf-1", "racf-2", "racf-3", "racf-4", "racf-5", "racf-link", "racf-6", "racf-7", "racf-link-2")
#: The battery ``racf scorecard`` runs unless told: the stop-sign battery the leaderboard's paper rows follow.
DEFAULT_BATTERY = "racf-4"
