"""The paper's four training losses (torch), weighted more on low-confidence steps."""

from __future__ import annotations

__all__ = ["LossWeights", "odca_losses"]

from dataclasses import dataclass


@dataclass(frozen=True)
class LossWeights:
    """lambda_ID, lambda_Delta0, lambda_cons, lambda_kin and the low-confidence emphasis kappa
    (a step's weight is 1 + kappa (1 - c~))."""

    identity: float = 3.0
    minimal_change: float = 0.01
    consistency: float = 1.0
    kinematics: float = 0.1
    low_confidence_emphasis: float = 4.0


def odca_losses(delta, base, d, c, l_al, v, clean, valid_pair, dt: float, tau_low: float, weights: LossWeights,
                lidar_trusted=None):
    """Returns (total, parts) for one batch of steps (1-D tensors, NaN already masked by the flags).

    Args:
        delta: predicted corrections (0 where the depth passed). base: what they add to (the
            witness the gate's verdict rests on).
        d: measured depth with NaN replaced by 0; ``clean`` marks steps that are unattacked,
            confident and measured (identity preservation applies there).
        l_al: aligned LiDAR with NaN replaced by 0 (``l_ok`` is l_al > 0).
        v: speed. valid_pair: step t and t-1 are in the same series (kinematics applies).
        lidar_trusted: where the LiDAR reference is plausible (agrees with the temporal prior);
            consistency applies only there. The cluster picked near the detection's bearing is
            sometimes another, farther object, and pulling the repair onto it would corrupt clean
            depth (the paper's own caveat: LiDAR is a trigger, not a substitute).
    """
    import torch

    d_rep = base + delta
    omega = 1.0 + weights.low_confidence_emphasis * (1.0 - c)
    l_ok = l_al > 0
    measured = d > 0
    disagree = l_ok & (~measured | ((d - l_al).abs() > tau_low))
    if lidar_trusted is not None:
        disagree = disagree & lidar_trusted

    def mean(x, mask):
        return (x * mask).sum() / mask.sum().clamp(min=1)

    parts = {
        "identity": mean(omega * (d_rep - d) ** 2, clean.float()),
        "minimal_change": mean(omega * delta**2, torch.ones_like(delta)),
        "consistency": mean(omega * (d_rep - l_al) ** 2, disagree.float()),
        "kinematics": mean(omega[1:] * (d_rep[1:] - d_rep[:-1] + v[1:] * dt) ** 2, valid_pair[1:].float()),
    }
    total = (weights.identity * parts["identity"] + weights.minimal_change * parts["minimal_change"]
             + weights.consistency * parts["consistency"] + weights.kinematics * parts["kinematics"])
    return total, parts
