"""The gate that votes: depth, LiDAR, kinematics and the sign's size are four witnesses of one distance.

Per step, with d~ the depth, l the aligned LiDAR reference, d_kin the kinematic branch and
d_size the size witness (the distance the detection's box implies from the sign's known
size; each may be missing):

- The size witness is one-sided. An occluder or a sticker can hide rows of the sign's face
  but never add any, so the box only ever shrinks and d_size errs long. A depth, a LiDAR or
  a d_kin *beyond* it (more than ``size_tol`` farther) is no longer possible: it is vetoed (a
  frustum spoof pushing depth and LiDAR away together; a LiDAR on the wall behind a sign
  its scan plane misses). A witness nearer than d_size is not: the box may be occluded.

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
- Within the size witness's tolerance, depth is confirmed by it when nothing else can: at
  first sight, with no LiDAR and no d_kin, it passes. With no depth, no trusted LiDAR and no
  d_kin (a blackout from first sight where the scan plane misses the plate), the repair rests
  on d_size (after an unconfirmed depth, which is nearer than it and so the safer).

Without a size witness (d_size NaN) the gate is the three-witness gate it was.

With ``kinematics_votes=False`` (the two-witness gate of the paper, an ablation) d_kin
does not vote: only the LiDAR confirms the depth, and any LiDAR is trusted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["GateConfig", "SOURCES", "vote", "BASELINE", "SIZE"]

#: What a step's output rests on (the ``source`` code of a fused sample indexes this).
SOURCES = ("depth", "lidar", "lidar+kinematics", "kinematics", "depth (unconfirmed)", "prior", "none",
           "kinematic baseline", "size")
DEPTH, LIDAR, LIDAR_KIN, KIN, DEPTH_UNCONFIRMED, PRIOR, NONE, BASELINE, SIZE = range(len(SOURCES))


@dataclass(frozen=True)
class GateConfig:
    """The gate's tolerances.

    Attributes:
        tau_m: depth and LiDAR agree within this residual, m (calibrated as a high
            percentile of clean residuals). Also the measurement tolerance of the
            kinematic witness and the bound on the head's correction.
        trust_confidence: with no other witness at all, a depth of at least this
            confidence passes (1.01: never).
        size_sigma: a witness agrees with d_size within ``tau_m + size_sigma * size_std``.
    """

    tau_m: float = 0.10
    trust_confidence: float = 1.01
    size_sigma: float = 3.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.tau_m) and 0.0 < self.tau_m <= 10.0):
            raise ValueError(f"tau_m must be in (0, 10] m, got {self.tau_m}")
        if not 0.0 <= self.trust_confidence <= 1.01:
            raise ValueError(f"trust_confidence must be in [0, 1.01] (1.01: never trust an unconfirmed depth), "
                             f"got {self.trust_confidence}")
        if not (math.isfinite(self.size_sigma) and 0.0 <= self.size_sigma <= 20.0):
            raise ValueError(f"size_sigma must be in [0, 20], got {self.size_sigma}")

    def size_tolerance(self, size_std: float) -> float:
        """How far a witness may lie from d_size and agree with it, m (NaN without a size witness)."""
        return self.tau_m + self.size_sigma * size_std


def vote(d: float, c: float, l: float, k: float, k_tol: float, mu: float, gate: GateConfig,
         kinematics_votes: bool = True, lidar_unconfirmed: bool = False, size: float = math.nan,
         size_tol: float = math.nan, k_echoes_depth: bool = False) -> tuple[int, float, bool]:
    """One step's verdict: (source, base, lidar_trusted).

    Args:
        d, c: depth (NaN: missing) and its confidence. l: aligned LiDAR (NaN: none).
        k, k_tol: d_kin (NaN: no branch) and how far a witness may lie from it.
        mu: the prior's forecast (NaN: none).
        lidar_unconfirmed: the LiDAR's track (and d_kin, anchored on it alone) never had a
            depth agree with it: it may be the background behind a sign the scan plane
            misses. Then it is one witness, not two, and a confident depth that disagrees
            with it passes (and takes over the branch).
        size, size_tol: d_size (NaN: no size witness) and how far a witness may lie from it.
        k_echoes_depth: d_kin rests on a depth nothing confirmed (anchored at a first sight with
            no other witness). Against a confirmed LiDAR it is no second witness for the depth:
            depth and LiDAR meet one to one, as they would had they arrived together.

    Returns the source code (``SOURCES``), the value the output rests on (the depth itself
    when it passes; NaN when there is no target) and whether the LiDAR counts as a trusted
    measurement this step.
    """
    s_ok = size == size and size_tol == size_tol
    # Beyond the size witness: farther than a box that can only shrink allows.
    d_vetoed = s_ok and d == d and d > size + size_tol
    if s_ok and l == l and l > size + size_tol:
        l = math.nan
    if s_ok and k == k and k > size + size_tol:
        k = math.nan
    d_ok, l_ok = d == d, l == l  # not NaN (inputs are sanitised: finite or NaN)
    k_ok = k == k
    k_votes = k_ok and kinematics_votes
    agree_dl = d_ok and l_ok and abs(d - l) <= gate.tau_m
    echo = k_echoes_depth and l_ok and not lidar_unconfirmed
    agree_dk = d_ok and k_votes and abs(d - k) <= k_tol and not echo
    agree_lk = l_ok and k_ok and abs(l - k) <= k_tol
    # LiDAR and kinematics agree; the depth is off the LiDAR and off d_kin by more than tau.
    outvoted = agree_lk and not agree_dl and abs(d - k) > gate.tau_m
    if not d_vetoed:
        if agree_dl or (agree_dk and not outvoted):
            return DEPTH, d, agree_dl
        if lidar_unconfirmed and d_ok and c >= gate.trust_confidence:
            return DEPTH, d, False
        if d_ok and not l_ok and not k_votes and (c >= gate.trust_confidence or (s_ok and abs(d - size) <= size_tol)):
            return DEPTH, d, False
    lidar_trusted = l_ok and (agree_lk or not k_votes or echo)
    if lidar_trusted:
        return (LIDAR_KIN if agree_lk else LIDAR), l, True
    if k_ok:
        return KIN, k, False
    if d_ok and not d_vetoed:
        return DEPTH_UNCONFIRMED, d, False
    if s_ok:
        return SIZE, size, False
    if mu == mu:
        return PRIOR, mu, False
    return NONE, math.nan, False
