"""The LiDAR consistency gate and the conservative fusion (the paper's Algorithm 1, Proposition 1)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GateConfig", "gate_weight", "fuse"]


@dataclass(frozen=True)
class GateConfig:
    """w = clip((r_XS - tau_low) / (tau_high - tau_low), 0, 1) ** gamma.

    Without a LiDAR reference there is no disagreement to measure: a depth with confidence
    >= ``trust_confidence`` then passes unchanged (w = 0), anything less is repaired
    (w = 1), and a missing depth is always repaired.

    Attributes:
        tau_low: residual (m) at and below which the measurement passes unchanged.
        tau_high: residual (m) at and above which the repair is used fully.
        gamma: shape exponent (> 0).
        trust_confidence: with no LiDAR, the confidence at and above which the depth passes.
    """

    tau_low: float = 0.10
    tau_high: float = 0.40
    gamma: float = 1.0
    trust_confidence: float = 1.01

    def __post_init__(self) -> None:
        if not (0.0 <= self.tau_low < self.tau_high <= 10.0):
            raise ValueError(f"need 0 <= tau_low < tau_high <= 10 m, got {self.tau_low}, {self.tau_high}")
        if not 0.05 <= self.gamma <= 20.0:
            raise ValueError(f"gamma must be in [0.05, 20], got {self.gamma}")
        if not 0.0 <= self.trust_confidence <= 1.01:
            raise ValueError(f"trust_confidence must be in [0, 1.01] (1.01: never trust without LiDAR), "
                             f"got {self.trust_confidence}")


def gate_weight(r_xs: np.ndarray | float, config: GateConfig, depth: np.ndarray | float = np.nan,
                confidence: np.ndarray | float = 0.0) -> np.ndarray:
    """Gate weight in [0, 1].

    A NaN residual (no LiDAR or no depth) gives 1 (repair only), except for a finite depth
    whose confidence reaches ``config.trust_confidence``, which passes (0).
    """
    r = np.asarray(r_xs, float)
    w = np.clip((r - config.tau_low) / (config.tau_high - config.tau_low), 0.0, 1.0) ** config.gamma
    trusted = np.isfinite(np.asarray(depth, float)) & (np.asarray(confidence, float) >= config.trust_confidence)
    return np.where(np.isfinite(r), w, np.where(trusted, 0.0, 1.0))


def fuse(d_meas: np.ndarray | float, d_rep: np.ndarray | float, w: np.ndarray | float) -> np.ndarray:
    """(1 - w) d~ + w d_rep; where w == 0 the measurement passes through exactly, where w == 1 the repair."""
    d, rep, w = (np.asarray(v, float) for v in (d_meas, d_rep, w))
    mixed = (1.0 - w) * np.where(np.isfinite(d), d, 0.0) + w * rep
    return np.where(w == 0.0, d, np.where(w == 1.0, rep, mixed))
