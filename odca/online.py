"""ODCA: the online, causal, per-step gated depth repair (the paper's Algorithm 1), and its batched twin.

Per step t: sanitise the inputs; the frozen prior forecasts the next ``horizon`` steps from
the last ``context_length`` depth measurements every ``refresh_steps`` steps (mu(t),
sigma(t) are read off the current forecast); the delta head predicts Delta(t); the
repaired distance is base + Delta with base = d~ (else mu, else the aligned LiDAR, else the
last valid depth); the gate weighs repair against measurement by the depth-LiDAR residual.
``run(df)`` computes the same numbers for whole series at once (the prior's windows batched
in the same fixed-size batches, the head row by row), so it matches ``step`` exactly.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from odca.align import Alignment, fit_alignment
from odca.features import MAX_RANGE_M, base_distance, features, sanitize, usable_forecast
from odca.gate import GateConfig, fuse, gate_weight
from odca.head import HeadWeights
from odca.prior import SHIPPED_PRIOR, Chronos2Prior, CheckpointError, TemporalPrior

__all__ = ["ODCA", "ODCAConfig", "FusedSample", "SHIPPED_HEAD"]

SHIPPED_HEAD = Path(__file__).resolve().parents[1] / "assets" / "checkpoints" / "odca-head"
_FALLBACK_M = 0.0  # nothing ever measured: report 0 m, the conservative (brake) answer


@dataclass(frozen=True)
class ODCAConfig:
    """ODCA's settings (saved as ``odca.json`` beside the head's weights).

    Attributes:
        context_length: prior context W, steps.
        horizon: prior horizon H, steps.
        refresh_steps: the prior forecasts every this many steps.
        dt: sample period, seconds.
        gate: gate thresholds.
        alignment: LiDAR -> depth map.
        prior: prior checkpoint: ``"shipped"`` (the project's own), a path (absolute or relative to
            the ODCA folder) or a hub id.
    """

    context_length: int = 64
    horizon: int = 16
    refresh_steps: int = 4
    dt: float = 0.02
    gate: GateConfig = field(default_factory=GateConfig)
    alignment: Alignment = field(default_factory=Alignment)
    prior: str = "shipped"

    def __post_init__(self) -> None:
        if not 1 <= self.refresh_steps <= self.horizon:
            raise ValueError(f"refresh_steps must be in [1, horizon={self.horizon}], got {self.refresh_steps}")
        if not 0 < self.dt <= 1.0:
            raise ValueError(f"dt must be in (0, 1] s, got {self.dt}")

    def to_json(self) -> dict:
        return {**asdict(self), "gate": asdict(self.gate), "alignment": asdict(self.alignment)}

    @classmethod
    def from_json(cls, raw: dict) -> "ODCAConfig":
        raw = dict(raw)
        raw["gate"] = GateConfig(**raw.get("gate", {}))
        raw["alignment"] = Alignment(**raw.get("alignment", {}))
        return cls(**raw)


@dataclass(frozen=True)
class FusedSample:
    """One step's output: the fused distance, the gate, the repair and the residuals (metres)."""

    d_fused: float
    w: float
    d_rep: float
    r_xs: float
    r_delta: float
    r_post: float
    mu: float
    sigma: float


class ODCA:
    """The Object Distance Correction Algorithm.

    Example:
        >>> from odca import ODCA
        >>> m = ODCA.load()
        >>> out = m.step(depth=1.50, confidence=0.9, lidar=1.62, speed=1.0)
        >>> round(out.d_fused, 3), out.w
        (1.5, 0.0)
    """

    def __init__(self, config: ODCAConfig, head: HeadWeights, prior: TemporalPrior) -> None:
        self.config = config
        self.head = head
        self.prior = prior
        self.reset()

    # -- loading and saving ----------------------------------------------------------------
    @classmethod
    def load(cls, path: str | Path | None = None, prior: TemporalPrior | None = None) -> "ODCA":
        """Loads ``odca.json`` + ``head.npz`` from ``path`` (default: the shipped ones) and the prior."""
        folder = Path(path) if path is not None else SHIPPED_HEAD
        cfg_file, weights_file = folder / "odca.json", folder / "head.npz"
        if not cfg_file.exists() or not weights_file.exists():
            raise CheckpointError(f"no ODCA checkpoint at {folder} (need odca.json and head.npz; `racf train` makes one)")
        try:
            config = ODCAConfig.from_json(json.loads(cfg_file.read_text()))
            with np.load(weights_file) as z:
                head = HeadWeights({k: z[k] for k in z.files})
        except (ValueError, TypeError, KeyError, OSError, json.JSONDecodeError) as err:
            raise CheckpointError(f"the ODCA checkpoint at {folder} is corrupt: {type(err).__name__}: {err}") from None
        if prior is None:
            if config.prior == "shipped":
                prior = Chronos2Prior(SHIPPED_PRIOR)
            else:
                prior_path = Path(config.prior)
                if not prior_path.is_absolute() and (folder / prior_path).exists():
                    prior_path = folder / prior_path
                prior = Chronos2Prior(prior_path if prior_path.exists() else config.prior)
        return cls(config, head, prior)

    def save(self, path: str | Path) -> None:
        folder = Path(path)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "odca.json").write_text(json.dumps(self.config.to_json(), indent=1))
        np.savez(folder / "head.npz", **self.head.a)

    # -- calibration -------------------------------------------------------------------------
    def calibrate(self, depth: np.ndarray, lidar: np.ndarray, confidence: np.ndarray | None = None) -> Alignment:
        """Fits the LiDAR alignment from paired arrays (robust regression) and keeps it for the run."""
        alignment = fit_alignment(depth, lidar, confidence)
        self.config = ODCAConfig.from_json({**self.config.to_json(), "alignment": asdict(alignment)})
        return alignment

    # -- online ----------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the past (a new run)."""
        self._context = np.full(self.config.context_length, np.nan)
        self._t = 0
        self._mean = np.full(self.config.horizon, np.nan)
        self._std = np.full(self.config.horizon, np.nan)
        self._d_prev = math.nan
        self._hold = _FALLBACK_M

    def step(self, *, depth: float, confidence: float, lidar: float = math.nan, speed: float = 0.0,
             dt: float | None = None) -> FusedSample:
        """One causal step. Any input may be NaN, inf, zero or negative (treated as missing).

        Args:
            depth: d~(t), metres. confidence: c~(t) in [0, 1]. lidar: l(t), metres.
            speed: vehicle speed, m/s. dt: sample period (default the config's).
        """
        for name, value in (("depth", depth), ("confidence", confidence), ("lidar", lidar), ("speed", speed)):
            if np.ndim(value) != 0:
                raise ValueError(f"{name} must be a scalar per step, got shape {np.shape(value)}; use run(df) for series")
        dt = self.config.dt if dt is None else float(dt)
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive finite number of seconds, got {dt}")
        k = self._t % self.config.refresh_steps
        if k == 0:
            mean, std = usable_forecast(*self.prior.forecast(self._context[None], self.config.horizon))
            self._mean, self._std = mean[0], std[0]
        d, c, l, v = sanitize(depth, confidence, lidar, speed)
        out = self._compute(d[None], c[None], l[None], v[None], self._mean[k:k + 1], self._std[k:k + 1],
                            np.array([self._d_prev]), np.array([self._hold]), dt)
        self._context = np.roll(self._context, -1)
        self._context[-1] = float(d)
        if np.isfinite(d):
            self._hold = float(d)
        self._d_prev = float(d)
        self._t += 1
        return FusedSample(*(float(col[0]) for col in out))

    # -- batched offline path ------------------------------------------------------------------
    def run(self, df: pd.DataFrame) -> pd.DataFrame:
        """The same computation over whole series: returns d_fused, w, d_rep, r_xs, r_delta, r_post, mu, sigma.

        ``df`` needs ``d_meas``, ``c_meas``, ``lidar`` and ``speed`` columns (or ``depth``/``confidence``),
        optionally ``series_id`` (each series starts fresh). Rows keep their order and index.
        """
        cols = {"depth": _pick(df, "d_meas", "depth"), "confidence": _pick(df, "c_meas", "confidence"),
                "lidar": _pick(df, "lidar", None), "speed": _pick(df, "speed", None)}
        groups = df.groupby("series_id", sort=False).indices.values() if "series_id" in df else [np.arange(len(df))]
        out = np.full((len(df), 8), np.nan)
        for idx in (g for g in groups if len(g)):
            out[idx] = np.column_stack(self._run_series(*(cols[k][idx] for k in cols)))
        return pd.DataFrame(out, index=df.index, columns=[f.name for f in FusedSample.__dataclass_fields__.values()])

    def _run_series(self, depth, confidence, lidar, speed):
        return self._compute(*self.series_inputs(depth, confidence, lidar, speed), self.config.dt)

    def series_inputs(self, depth, confidence, lidar, speed):
        """Sanitised inputs of one series plus the prior's (mu, sigma), the previous depth and the hold value."""
        cfg = self.config
        d, c, l, v = sanitize(depth, confidence, lidar, speed)
        n = len(d)
        # Prior windows at the refresh steps: the last W depths before each.
        padded = np.concatenate([np.full(cfg.context_length, np.nan), d])
        starts = np.arange(0, n, cfg.refresh_steps)
        windows = np.stack([padded[s:s + cfg.context_length] for s in starts]) if n else np.empty((0, cfg.context_length))
        mean, std = usable_forecast(*self.prior.forecast(windows, cfg.horizon)) if n else (windows, windows)
        offset = np.arange(n) % cfg.refresh_steps
        mu, sigma = mean[np.arange(n) // cfg.refresh_steps, offset], std[np.arange(n) // cfg.refresh_steps, offset]
        d_prev = np.concatenate([[np.nan], d[:-1]])
        # The last valid depth before each step (the hold value), _FALLBACK_M before any.
        last = pd.Series(d).ffill().to_numpy()
        hold = np.concatenate([[_FALLBACK_M], np.nan_to_num(last[:-1], nan=_FALLBACK_M)])
        return d, c, l, v, mu, sigma, d_prev, hold

    # -- shared arithmetic ---------------------------------------------------------------------
    def _compute(self, d, c, l, v, mu, sigma, d_prev, hold, dt):
        l_al = self.config.alignment(l)
        x = features(d, c, l_al, v, mu, sigma, d_prev, hold, dt)
        return self.repair(x, d, c, l_al, base_distance(d, mu, l_al, hold), hold, mu, sigma)

    def repair(self, x, d, c, l_al, base, hold, mu=np.nan, sigma=np.nan):
        """Head, gate and fusion from precomputed features (training and scoring reuse it).

        Returns the ``FusedSample`` fields as arrays, in order.
        """
        delta = self.head(x)
        d_rep = base + delta
        r_xs = np.abs(d - l_al)  # NaN when either is missing -> w = 1
        w = gate_weight(r_xs, self.config.gate, d, c)
        d_fused = fuse(d, d_rep, w)
        # Never NaN or inf out: an unusable repair falls back to the hold value; and a distance
        # is never negative nor beyond the sensors' range.
        d_fused = np.clip(np.where(np.isfinite(d_fused), d_fused, hold), 0.0, MAX_RANGE_M)
        d_rep = np.clip(np.where(np.isfinite(d_rep), d_rep, hold), 0.0, MAX_RANGE_M)
        r_post = np.abs(d_fused - l_al)
        n = len(d_fused)
        return (d_fused, w, d_rep, r_xs, np.abs(delta), r_post, np.broadcast_to(mu, n), np.broadcast_to(sigma, n))


def _pick(df: pd.DataFrame, name: str, alt: str | None) -> np.ndarray:
    if name in df:
        return df[name].to_numpy(float)
    if alt is not None and alt in df:
        return df[alt].to_numpy(float)
    raise ValueError(f"run(df) needs a {name!r} column" + (f" (or {alt!r})" if alt else "") +
                     f"; got columns {list(df.columns)}")
