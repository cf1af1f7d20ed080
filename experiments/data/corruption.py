"""Offline corruption of recorded clean distance series: the protocol's weak / mid / strong presets.

Corruption comes in non-overlapping segments covering a preset share of the series. Each
segment is one of:

- ``bias``: a constant offset of random sign (depth and confidence otherwise unchanged:
  the stealthy attack);
- ``blackout``: depth invalid (NaN), confidence 0;
- ``degradation``: confidence times the preset multiplier, plus Gaussian noise.

A preset fixes the blackout share of segments; the rest split evenly between bias and
degradation. Labels are 1 inside a segment, 0 elsewhere. The generator is seeded by what a
series is (:func:`draw_seed`: its drive's seed, the preset and the draw's index), so every
method sees identical corrupted input and an edit to the code redraws nothing.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

__all__ = ["CorruptionPreset", "PRESETS", "SEGMENT_KINDS", "Corrupted", "corrupt_series", "draw_seed"]

SEGMENT_KINDS = ("none", "bias", "blackout", "degradation")


@dataclass(frozen=True)
class CorruptionPreset:
    """One row of the protocol's table.

    Attributes:
        name: preset name.
        share: share of samples inside segments.
        segment_s: (min, max) segment length, seconds.
        bias_m: (min, max) bias magnitude, metres.
        blackout_share: share of segments that are blackouts.
        confidence_multiplier: confidence factor in degradation segments.
        noise_std_m: noise std in degradation segments, metres.
    """

    name: str
    share: float
    segment_s: tuple[float, float]
    bias_m: tuple[float, float]
    blackout_share: float
    confidence_multiplier: float
    noise_std_m: float

    def __post_init__(self) -> None:
        if not 0.0 <= self.share < 1.0:
            raise ValueError(f"share must be in [0, 1), got {self.share}")
        for name in ("segment_s", "bias_m"):
            lo, hi = getattr(self, name)
            if not 0.0 <= lo <= hi:
                raise ValueError(f"{name} must be (min, max) with 0 <= min <= max, got {(lo, hi)}")
        if self.segment_s[0] <= 0:
            raise ValueError(f"segment_s must be > 0 s, got {self.segment_s}")
        for name in ("blackout_share", "confidence_multiplier"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {getattr(self, name)}")
        if self.noise_std_m < 0:
            raise ValueError(f"noise_std_m must be >= 0, got {self.noise_std_m}")


PRESETS: dict[str, CorruptionPreset] = {
    "weak": CorruptionPreset("weak", 0.10, (0.2, 1.0), (0.10, 0.25), 0.20, 0.7, 0.03),
    "mid": CorruptionPreset("mid", 0.20, (0.3, 1.5), (0.25, 0.50), 0.35, 0.5, 0.06),
    "strong": CorruptionPreset("strong", 0.35, (0.5, 3.0), (0.50, 1.00), 0.50, 0.3, 0.10),
}


@dataclass(frozen=True)
class Corrupted:
    """A corrupted series.

    Attributes:
        depth: (T,) corrupted distance, metres (NaN in blackouts).
        confidence: (T,) corrupted confidence in [0, 1].
        label: (T,) int8, 1 inside a segment.
        kind: (T,) int8 index into ``SEGMENT_KINDS``.
    """

    depth: np.ndarray
    confidence: np.ndarray
    label: np.ndarray
    kind: np.ndarray


def draw_seed(drive_seed: int, preset: str, draw: int = 0) -> int:
    """The seed of one corruption draw of a drive: a function of (the drive's seed, the preset's
    name, the draw's index) only, stable across runs, processes, machines and code versions."""
    if drive_seed < 0 or draw < 0:
        raise ValueError(f"drive_seed and draw must be >= 0, got {drive_seed}, {draw}")
    return int(np.random.SeedSequence([int(drive_seed), zlib.crc32(preset.encode()), int(draw)])
               .generate_state(1)[0])


def corrupt_series(depth: np.ndarray, confidence: np.ndarray, preset: str | CorruptionPreset, seed: int,
                   dt: float = 0.02) -> Corrupted:
    """Corrupts one clean series.

    Args:
        depth: (T,) clean distance, metres (NaN allowed: no measurement).
        confidence: (T,) clean confidence in [0, 1].
        preset: ``"weak"``, ``"mid"``, ``"strong"`` or a ``CorruptionPreset``.
        seed: the draw's seed (see :func:`draw_seed`).
        dt: sample period, seconds.
    """
    p = PRESETS.get(preset) if isinstance(preset, str) else preset
    if p is None:
        raise ValueError(f"preset must be one of {sorted(PRESETS)} or a CorruptionPreset, got {preset!r}")
    depth = np.asarray(depth, float)
    confidence = np.asarray(confidence, float)
    if depth.ndim != 1 or depth.shape != confidence.shape:
        raise ValueError(f"depth and confidence must be 1-D of the same length, got {depth.shape}, {confidence.shape}")
    if not dt > 0:
        raise ValueError(f"dt must be > 0 s, got {dt}")
    rng = np.random.default_rng(seed)
    n = depth.size
    kind = np.zeros(n, np.int8)
    out_d, out_c = depth.copy(), confidence.copy()
    target = int(round(p.share * n))
    lo, hi = (max(1, int(round(s / dt))) for s in p.segment_s)
    covered, attempts = 0, 0
    while covered < target and attempts < 1000:
        attempts += 1
        length = min(int(rng.integers(lo, hi + 1)), target - covered if target - covered >= lo else lo, n)
        start = int(rng.integers(0, n - length + 1))
        # Keep segments apart so each is one attack; retry elsewhere on overlap.
        if kind[max(0, start - 1):start + length + 1].any():
            continue
        u = rng.random()
        k = 2 if u < p.blackout_share else (1 if u < p.blackout_share + (1 - p.blackout_share) / 2 else 3)
        seg = slice(start, start + length)
        kind[seg] = k
        if k == 1:
            out_d[seg] += rng.choice((-1.0, 1.0)) * rng.uniform(*p.bias_m)
        elif k == 2:
            out_d[seg], out_c[seg] = np.nan, 0.0
        else:
            out_c[seg] *= p.confidence_multiplier
            out_d[seg] += rng.normal(0.0, p.noise_std_m, length)
        covered += length
    return Corrupted(out_d, np.clip(out_c, 0.0, 1.0), (kind > 0).astype(np.int8), kind)
