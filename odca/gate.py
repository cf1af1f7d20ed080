"""The gate that votes: depth, LiDAR and kinematics are three witnesses of one distance.

Per step, with d~ the depth, l the aligned LiDAR reference and d_kin the kinematic branch
(each may be missing):

- Depth passes unchanged (w = 0) when it agrees with at least one other witness: with the
  LiDAR within ``tau_m``, or with d_kin within ``tau_m + n_sigma * std_kin``. Clean depth
  agrees with its witnesses, so it is never changed (the paper's Proposition 1). One
  exception: when the LiDAR and d_kin agree with each other and the depth lies more than
  ``tau_m`` from both, two witnesses outvote it even if it lies inside d_kin's (wider)
  tolerance; else a depth ramped slowly inside that tolerance would pass against an honest
  LiDAR.
  With no other witness at all (the first sight of a target), a depth of confidence
  >= ``trust_confidence`` passes: there is nothing to vote against it.
- Otherwise the depth is outvoted or missing and the step is repaired (w = 1) from the
  witnesses that agree, in this order: the LiDAR where it agrees with d_kin (or there is no
  d_kin); d_kin; an unconfirmed depth; the temporal prior's forecast; else nothing (no
  target: NaN). A LiDAR that disagrees with both the depth and d_kin (a spoof) is never
  used.

With ``kinematics_votes=False`` (the two-witness gate of the paper, an ablation) d_kin
does not vote: only the LiDAR confirms the depth, and any LiDAR is trusted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["GateConfig", "SOURCES", "vote", "BASELINE"]

#: What a step's output rests on (the ``source`` code of a fused sample indexes this).
SOURCES = ("depth", "lidar", "lidar+kinematics", "kinematics", "depth (unconfirmed)", "prior", "none",
           "kinematic baseline")
DEPTH, LIDAR, LIDAR_KIN, KIN, DEPTH_UNCONFIRMED, PRIOR, NONE, BASELINE = range(len(SOURCES))


@dataclass(frozen=True)
class GateConfig:
    """The gate's tolerances.

    Attributes:
        tau_m: depth and LiDAR agree within this residual, m (calibrated as a high
            percentile of clean residuals). Also the measurement tolerance of the
            kinematic witness and the bound on the head's correction.
        trust_confidence: with no other witness at all, a depth of at least this
            confidence passes (1.01: never).
    """

    tau_m: float = 0.10
    trust_confidence: float = 1.01

    def __post_init__(self) -> None:
        if not (math.isfinite(self.tau_m) and 0.0 < self.tau_m <= 10.0):
            raise ValueError(f"tau_m must be in (0, 10] m, got {self.tau_m}")
        if not 0.0 <= self.trust_confidence <= 1.01:
            raise ValueError(f"trust_confidence must be in [0, 1.01] (1.01: never trust an unconfirmed depth), "
                             f"got {self.trust_confidence}")


def vote(d: float, c: float, l: float, k: float, k_tol: float, mu: float, gate: GateConfig,
         kinematics_votes: bool = True, lidar_unconfirmed: bool = False) -> tuple[int, float, bool]:
    """One step's verdict: (source, base, lidar_trusted).

    Args:
        d, c: depth (NaN: missing) and its confidence. l: aligned LiDAR (NaN: none).
        k, k_tol: d_kin (NaN: no branch) and how far a witness may lie from it.
        mu: the prior's forecast (NaN: none).
        lidar_unconfirmed: the LiDAR's track (and d_kin, anchored on it alone) never had a
            depth agree with it: it may be the background behind a sign the scan plane
            misses. Then it is one witness, not two, and a confident depth that disagrees
            with it passes (and takes over the branch).

    Returns the source code (``SOURCES``), the value the output rests on (the depth itself
    when it passes; NaN when there is no target) and whether the LiDAR counts as a trusted
    measurement this step.
    """
    d_ok, l_ok = d == d, l == l  # not NaN (inputs are sanitised: finite or NaN)
    k_ok = k == k
    k_votes = k_ok and kinematics_votes
    agree_dl = d_ok and l_ok and abs(d - l) <= gate.tau_m
    agree_dk = d_ok and k_votes and abs(d - k) <= k_tol
    agree_lk = l_ok and k_ok and abs(l - k) <= k_tol
    # LiDAR and kinematics agree; the depth is off the LiDAR and off d_kin by more than tau.
    outvoted = agree_lk and not agree_dl and abs(d - k) > gate.tau_m
    if agree_dl or (agree_dk and not outvoted):
        return DEPTH, d, agree_dl
    if lidar_unconfirmed and d_ok and c >= gate.trust_confidence:
        return DEPTH, d, False
    if d_ok and not l_ok and not k_votes and c >= gate.trust_confidence:
        return DEPTH, d, False
    lidar_trusted = l_ok and (agree_lk or not k_votes)
    if lidar_trusted:
        return (LIDAR_KIN if agree_lk else LIDAR), l, True
    if k_ok:
        return KIN, k, False
    if d_ok:
        return DEPTH_UNCONFIRMED, d, False
    if mu == mu:
        return PRIOR, mu, False
    return NONE, math.nan, False
