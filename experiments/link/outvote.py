"""A served answer is one more reading: the car's own witnesses outvote one that says the target is
farther than they do, or that nothing stands where they see it stand.

A lie the protocol's check cannot see (a distance in range, the ids kept: ``racf.experiments.link.wire``
refuses only what no honest service sends) must cost the car nothing it would not have without the
service. So the served distance drives only where the car's own defence (its onboard one, run every
step beside the served one, else its depth distance) does not put the target nearer; a served
distance nearer than the car's own is on the safe side and drives.
"""

from __future__ import annotations

import math

__all__ = ["outvote", "OUTVOTE_M"]

#: A served distance farther than the car's own by more than this is outvoted, m (the depth reads the
#: sign's face, a defence its repaired face; two honest defences agree to a few centimetres).
OUTVOTE_M = 0.15


def outvote(served_m: float, served_stands: bool | None, own_m: float,
            own_stands: bool | None) -> tuple[float, bool | None, bool]:
    """The distance and verdict the car acts on, and whether the served answer was outvoted: the served
    ones unless the car's own say the target is nearer (by more than ``OUTVOTE_M``) or stands where
    the service says nothing does."""
    outvoted = False
    if math.isfinite(own_m) and (not math.isfinite(served_m) or served_m > own_m + OUTVOTE_M):
        served_m, outvoted = own_m, True
    if served_stands is False and own_stands:
        served_stands, outvoted = True, True  # the car's own witnesses see it stand
    return served_m, served_stands, outvoted
