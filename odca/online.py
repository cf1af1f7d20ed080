"""ODCA online: the causal, per-step repair of the depth distance (the paper's Algorithm 1 with
the RACF framework's kinematic branch), and its batched twin.

Per step t:

1. sanitise the inputs; the frozen prior forecasts the next ``horizon`` steps from the last
   ``context_length`` depths every ``refresh_steps`` steps (mu(t), sigma(t) are read off the
   current forecast);
2. the kinematic branch advances the last trusted distance by the car's odometry
   (:mod:`racf.odca.kinematics`);
3. the gate votes among depth, LiDAR, kinematics and the sign's size (:mod:`racf.odca.gate`):
   depth that agrees with a witness passes unchanged; otherwise the repair rests on the
   witnesses that agree, and the delta head adds its correction, bounded by the gate's
   tolerance. The size witness vetoes whatever lies beyond it and, when nothing else is left,
   anchors the kinematic branch (later sizes refine a branch that rests on it alone);
4. a trusted measurement re-anchors the kinematic branch: the LiDAR, or a depth the LiDAR
   confirms (a depth that passed on the branch's word alone does not, else a depth ramped
   inside the branch's tolerance would drag the branch along; issue 23). A depth within tau of
   the LiDAR may still carry a bias up to tau, so against an honest LiDAR a ramp is held within
   about 2 tau (anchoring on the LiDAR instead would hold it to tau, but would outvote the clean
   depth-LiDAR residual's tail: 99.1 % of clean depth unchanged, not 99.9 %). A measurement off
   the branch's odometry-only baseline (``KinematicBranch.drifted``; a depth repeated from a held
   camera frame is compared as of its frame; a moving target's baseline spreads with its speed's
   uncertainty, ``follow_moving_target``) is outvoted instead, depth and LiDAR together: the step
   rests on the baseline. A LiDAR
   track that no depth ever confirmed (``lidar_confirmed=False``: perception started it while
   the depth was missing) counts as one witness, and so does a branch anchored on it alone:
   a confident depth that disagrees with them passes;
5. a repair moves the output no further per step than the car's motion plus the tolerance of
   a fresh measurement (``step_bound_m``); a depth that passed is output as it is, and the
   head corrects only repairs that rest on a witness (``corrected``). The output is NaN when
   there is no target at all.

``run(df)`` computes the same numbers for whole series (the prior's windows batched in the
same fixed-size batches, the head row by row), so it matches ``step`` exactly.
"""

from __future__ import annotations

import copy
import json
import math
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np
import pandas as pd

from racf.odca.align import Alignment, fit_alignment
from racf.odca.features import MAX_RANGE_M, features, sanitize, sanitize_size, usable_forecast
from racf.odca.gate import DEPTH, SOURCES, GateConfig, vote
from racf.odca.head import HeadWeights
from racf.odca.kinematics import KinematicsConfig
from racf.odca.prior import CheckpointError, TemporalPrior, checkpoint_prior
from racf.odca.series import _optional, _pick, corrected, segments
from racf.odca.witnesses import Witnesses, bounded
from racf.assets import asset_path

__all__ = ["ODCA", "ODCAConfig", "FusedSample", "SHIPPED_HEAD", "SOURCES", "RUNTIMES", "read_checkpoint"]

SHIPPED_HEAD = asset_path("checkpoints", "odca-head")
#: Where the prior and the head run: PyTorch (and numpy) in the car's process, or onnxruntime on
#: the exported files (``racf odca export``).
RUNTIMES = ("torch", "onnx")


def read_checkpoint(folder: Path) -> tuple["ODCAConfig", dict]:
    """The config and the head's arrays of an ODCA folder; CheckpointError names what is wrong."""
    cfg_file, weights_file = folder / "odca.json", folder / "head.npz"
    if not cfg_file.exists() or not weights_file.exists():
        raise CheckpointError(f"no ODCA checkpoint at {folder} (need odca.json and head.npz; `racf odca train` makes one)")
    try:
        config = ODCAConfig.from_json(json.loads(cfg_file.read_text()))
        with np.load(weights_file) as z:
            arrays = {k: z[k] for k in z.files}
        HeadWeights(arrays)  # the shapes checked
    except (ValueError, TypeError, KeyError, OSError, json.JSONDecodeError) as err:
        raise CheckpointError(f"the ODCA checkpoint at {folder} is corrupt or from an older racf "
                              f"({type(err).__name__}: {err}); retrain it with `racf odca train`") from None
    return config, arrays


@dataclass(frozen=True)
class ODCAConfig:
    """ODCA's settings (saved as ``racf.odca.json`` beside the head's weights).

    Attributes:
        context_length: prior context W, steps.
        horizon: prior horizon H, steps.
        refresh_steps: the prior forecasts every this many steps.
        dt: sample period, seconds.
        gate: the gate's tolerances.
        kinematics: the kinematic branch.
        alignment: LiDAR -> depth map.
        prior: prior checkpoint: ``"shipped"`` (the project's own), a path (absolute or relative to
            the ODCA folder) or a hub id.
    """

    context_length: int = 64
    horizon: int = 16
    refresh_steps: int = 4
    dt: float = 0.02
    gate: GateConfig = field(default_factory=GateConfig)
    kinematics: KinematicsConfig = field(default_factory=KinematicsConfig)
    alignment: Alignment = field(default_factory=Alignment)
    prior: str = "shipped"

    def __post_init__(self) -> None:
        if not 1 <= self.refresh_steps <= self.horizon:
            raise ValueError(f"refresh_steps must be in [1, horizon={self.horizon}], got {self.refresh_steps}")
        if not 0 < self.dt <= 1.0:
            raise ValueError(f"dt must be in (0, 1] s, got {self.dt}")

    @property
    def step_bound_m(self) -> float:
        """How far the output may move per step beyond the car's own motion: the tolerance a
        witness has against a freshly anchored kinematic branch, m."""
        k = self.kinematics
        return self.gate.tau_m + k.n_sigma * k.anchor_std_m

    def to_json(self) -> dict:
        return {**asdict(self), "gate": asdict(self.gate), "kinematics": asdict(self.kinematics),
                "alignment": asdict(self.alignment)}

    @classmethod
    def from_json(cls, raw: dict) -> "ODCAConfig":
        raw = dict(raw)
        raw["gate"] = GateConfig(**raw.get("gate", {}))
        raw["kinematics"] = KinematicsConfig(**raw.get("kinematics", {}))
        raw["alignment"] = Alignment(**raw.get("alignment", {}))
        return cls(**raw)


@dataclass(frozen=True)
class FusedSample:
    """One step's output (distances in metres).

    Attributes:
        d_fused: the repaired distance; NaN when there is no target (nothing measured, no
            branch to carry one): no distance, never 0 m.
        w: 0 where the depth passed unchanged, 1 where the step was repaired (the attack flag).
        d_rep: the repair (base + the head's correction; NaN without a target).
        r_xs: |d~ - l|, the depth-LiDAR residual (NaN when either is missing).
        r_delta: |Delta|, the head's correction.
        r_post: |d_fused - l|.
        mu, sigma: the prior's forecast for this step.
        d_kin, kin_std: the kinematic branch and its std as the gate saw them: advanced to
            this step, before this step's anchor (NaN when there is no branch).
        source: what the output rests on, an index into ``SOURCES``.
    """

    d_fused: float
    w: float
    d_rep: float
    r_xs: float
    r_delta: float
    r_post: float
    mu: float
    sigma: float
    d_kin: float
    kin_std: float
    source: float

    @property
    def has_target(self) -> bool:
        return math.isfinite(self.d_fused)

    @property
    def source_name(self) -> str:
        return SOURCES[int(self.source)]


_COLUMNS = tuple(f.name for f in fields(FusedSample))


class ODCA:
    """The Object Distance Correction Algorithm.

    Example:
        >>> from odca import ODCA
        >>> m = ODCA.load()
        >>> out = m.step(depth=1.50, confidence=0.9, lidar=1.52, speed=1.0)
        >>> round(out.d_fused, 3), out.w, out.source_name
        (1.5, 0.0, 'depth')
    """

    def __init__(self, config: ODCAConfig, head: HeadWeights, prior: TemporalPrior) -> None:
        self.config = config
        self.head = head
        self.prior = prior
        self.reset()

    # -- loading and saving ----------------------------------------------------------------
    @classmethod
    def load(cls, path: str | Path | None = None, prior: TemporalPrior | None = None, runtime: str = "torch") -> "ODCA":
        """Loads ``racf.odca.json`` + ``head.npz`` from ``path`` (default: the shipped ones) and the prior.
        ``runtime="onnx"``: the folder ``racf odca export`` wrote (default: the shipped export), its
        prior and head run by onnxruntime (:mod:`racf.odca.onnx_runtime`)."""
        if runtime not in RUNTIMES:
            raise ValueError(f"runtime must be one of {RUNTIMES}, got {runtime!r}")
        if runtime == "onnx":
            from racf.odca.onnx_runtime import SHIPPED_ONNX, OnnxHead, OnnxPrior, read_export

            folder = Path(path) if path is not None else SHIPPED_ONNX
            manifest = read_export(folder)
            config, arrays = read_checkpoint(folder)
            return cls(config, OnnxHead(folder, arrays, manifest), prior or OnnxPrior(folder, manifest))
        folder = Path(path) if path is not None else SHIPPED_HEAD
        config, arrays = read_checkpoint(folder)
        return cls(config, HeadWeights(arrays), prior or checkpoint_prior(config.prior, folder))

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
        """Forget the past (a new run, or the track changed target)."""
        self._context = np.full(self.config.context_length, np.nan)
        self._t = 0
        self._mean = np.full(self.config.horizon, np.nan)
        self._std = np.full(self.config.horizon, np.nan)
        self._witnesses = Witnesses(self.config)
        self._prev = math.nan
        self._last_lidar = math.nan
        self._last_size = (math.nan, math.nan)
        self._lidar_confirmed = True

    moving_std_mps: float | None = None  # a moving target's speed uncertainty, m/s (None: a standing one)

    def follow_moving_target(self, speed_std_mps: float | None) -> None:
        """Its target moves (``speed``: the closing speed), its speed this uncertain, m/s (None: it stands)."""
        if speed_std_mps is not None and not (math.isfinite(speed_std_mps) and speed_std_mps >= 0):
            raise ValueError(f"speed_std_mps must be a finite number >= 0 m/s or None, got {speed_std_mps!r}")
        self.moving_std_mps = None if speed_std_mps is None else float(speed_std_mps)

    def step(self, *, depth: float, confidence: float, lidar: float = math.nan, speed: float = 0.0,
             yaw_rate: float = 0.0, bearing: float = math.nan, dt: float | None = None,
             lidar_confirmed: bool = True, size: float = math.nan, size_std: float = math.nan) -> FusedSample:
        """One causal step. Any input may be NaN, inf, zero or negative (treated as missing).

        Args:
            depth: d~(t), metres. confidence: c~(t) in [0, 1]. lidar: l(t), metres.
            speed: the car's speed, m/s. yaw_rate: its yaw rate, rad/s (left positive).
            bearing: the detection's bearing, rad (left positive; NaN: none).
            dt: time since the last step (default the config's).
            lidar_confirmed: whether a depth ever agreed with the LiDAR's track (perception knows:
                ``LidarTargetTracker.depth_confirmed``). A track started while the depth was missing may
                sit on the background behind a sign the scan plane misses: it counts as one witness, and
                a confident depth that disagrees with it passes (offline series: confirmed).
            size: the size witness d_size, m (``PerceptionSample.d_size``; NaN: none). It vetoes any
                witness farther than it, and bases the repair when nothing else can (:mod:`racf.odca.gate`).
            size_std: its std, m.
        """
        for name, value in (("depth", depth), ("confidence", confidence), ("lidar", lidar), ("speed", speed),
                            ("yaw_rate", yaw_rate), ("bearing", bearing), ("size", size), ("size_std", size_std)):
            if np.ndim(value) != 0:
                raise ValueError(f"{name} must be a scalar per step, got shape {np.shape(value)}; use run(df) for series")
        dt = self.config.dt if dt is None else float(dt)
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive finite number of seconds, got {dt}")
        if self._witnesses.config is not self.config:  # the config was replaced (calibration)
            self._witnesses = Witnesses(self.config)
        k = self._t % self.config.refresh_steps
        if k == 0:
            mean, std = usable_forecast(*self.prior.forecast(self._context[None], self.config.horizon))
            self._mean, self._std = mean[0], std[0]
        d, c, l, v, w, b = (float(x) for x in sanitize(depth, confidence, lidar, speed, yaw_rate, bearing))
        s, s_std = (float(x) for x in sanitize_size(size, size_std))
        l_al = float(self.config.alignment(l))
        mu, sigma = float(self._mean[k]), float(self._std[k])
        self._last_lidar = l_al
        self._last_size = (s, s_std)
        self._lidar_confirmed = bool(lidar_confirmed)
        verdict = self._witnesses.step(d, c, l_al, v, w, b, mu, dt, self._lidar_confirmed, s, s_std, self.moving_std_mps)
        cols = self._finish(*(np.array([x], float) for x in (d, c, l_al, v, mu, sigma, *verdict)), prev=self._prev)
        self._prev = float(cols[0][0])
        self._context[:-1] = self._context[1:]  # slide the window in place (np.roll allocates twice)
        self._context[-1] = d
        self._t += 1
        return FusedSample(*(float(col[0]) for col in cols))

    def would_pass(self, *, depth: float, speed: float = 0.0, yaw_rate: float = 0.0, lidar_shift: float = 0.0,
                   dt: float | None = None, size_shift: float = 0.0) -> bool:
        """Whether a next step with this depth would pass the gate unchanged (w = 0). Changes nothing.

        The LiDAR reference is taken as the last step's, moved by the car's motion and by
        ``lidar_shift`` m (a spoof that moves it with the depth); the size witness likewise,
        moved by ``size_shift`` m (an attack that scales the sign's image with the depth). The
        question a white-box attacker asks before it picks its bias.
        """
        cfg = self.config
        dt = cfg.dt if dt is None else float(dt)
        branch = copy.copy(self._witnesses.branch)
        motion = branch.predict(speed, yaw_rate, dt) if cfg.kinematics.enabled else math.nan
        if not motion == motion:
            motion = -speed * dt
        d = float(sanitize(depth, 1.0, math.nan, 0.0)[0])
        k = branch.distance
        l = self._last_lidar + motion + lidar_shift
        s, s_std = self._last_size
        source, base, _ = vote(d, 1.0, l, k, branch.tolerance(cfg.gate.tau_m) if k == k else math.nan, math.nan,
                               cfg.gate, cfg.kinematics.witness,
                               lidar_unconfirmed=self._witnesses.lidar_unconfirmed(l, self._lidar_confirmed, branch),
                               size=s + motion + size_shift, size_tol=cfg.gate.size_tolerance(s_std),
                               k_echoes_depth=cfg.kinematics.enabled and branch.depth_only)
        age_m = self._witnesses.peek_depth_age(d, motion, dt)
        return source == DEPTH and not (cfg.kinematics.enabled and branch.drifted(base, cfg.gate.tau_m, age_m))

    # -- batched offline path ------------------------------------------------------------------
    def run(self, df: pd.DataFrame) -> pd.DataFrame:
        """The same computation over whole series: one column per ``FusedSample`` field.

        ``df`` needs ``d_meas``, ``c_meas``, ``lidar`` and ``speed`` columns (or ``depth``/``confidence``),
        optionally ``yaw_rate``, ``bearing``, ``d_size`` and ``size_std`` (the size witness), ``series_id``
        (each series starts fresh) and ``slot`` (the car resets ODCA when its track changes target: so
        does a new slot). Rows keep their order and index.
        """
        cols = {"depth": _pick(df, "d_meas", "depth"), "confidence": _pick(df, "c_meas", "confidence"),
                "lidar": _pick(df, "lidar", None), "speed": _pick(df, "speed", None),
                "yaw_rate": _optional(df, "yaw_rate", 0.0), "bearing": _optional(df, "bearing", np.nan),
                "size": _optional(df, "d_size", np.nan), "size_std": _optional(df, "size_std", np.nan)}
        out = np.full((len(df), len(_COLUMNS)), np.nan)
        for idx in segments(df):
            out[idx] = np.column_stack(self.run_segment(*(cols[k][idx] for k in cols)))
        return pd.DataFrame(out, index=df.index, columns=list(_COLUMNS))

    def run_segment(self, depth, confidence, lidar, speed, yaw_rate, bearing, size=None, size_std=None):
        """One fresh run over one segment's arrays; returns the ``FusedSample`` fields as arrays."""
        inputs = self.segment_inputs(depth, confidence, lidar, speed, yaw_rate, bearing, size, size_std)
        return self._finish(*inputs, prev=math.nan)

    def segment_inputs(self, depth, confidence, lidar, speed, yaw_rate, bearing, size=None, size_std=None):
        """Sanitised inputs of one segment, the prior's (mu, sigma) and the gate's verdicts per step:
        (d, c, l_al, v, mu, sigma, source, base, lidar_trusted, d_kin, kin_std, motion). ``size``,
        ``size_std``: the size witness per step (None: none)."""
        d, c, l, v, w, b = sanitize(depth, confidence, lidar, speed, yaw_rate, bearing)
        l_al = np.asarray(self.config.alignment(l), float)
        mu, sigma = self.prior_inputs(d)
        return (d, c, l_al, v, mu, sigma, *self.verdicts(d, c, l_al, v, w, b, mu, size, size_std))

    def prior_inputs(self, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The prior's (mu, sigma) at every step of one segment's sanitised depths."""
        cfg = self.config
        n = len(d)
        # Prior windows at the refresh steps: the last W depths before each.
        padded = np.concatenate([np.full(cfg.context_length, np.nan), d])
        starts = np.arange(0, n, cfg.refresh_steps)
        windows = np.stack([padded[s:s + cfg.context_length] for s in starts]) if n else np.empty((0, cfg.context_length))
        mean, std = usable_forecast(*self.prior.forecast(windows, cfg.horizon)) if n else (windows, windows)
        row, offset = np.arange(n) // cfg.refresh_steps, np.arange(n) % cfg.refresh_steps
        return mean[row, offset], std[row, offset]

    def verdicts(self, d, c, l_al, v, w, b, mu, size=None, size_std=None):
        """The gate's verdicts over one segment (sanitised arrays), from a fresh kinematic branch:
        (source, base, lidar_trusted, d_kin, kin_std, motion)."""
        witnesses = Witnesses(self.config)
        n = len(d)
        nan = np.full(n, np.nan)
        s, s_std = sanitize_size(nan if size is None else size, nan if size_std is None else size_std)
        rows = [witnesses.step(d_, c_, l_, v_, w_, b_, mu_, self.config.dt, True, s_, e_) for d_, c_, l_, v_, w_, b_, mu_, s_, e_
                in zip(d.tolist(), c.tolist(), l_al.tolist(), v.tolist(), w.tolist(), b.tolist(), mu.tolist(),
                       s.tolist(), s_std.tolist())]
        source, base, trusted, k, k_std, motion = np.array(rows, float).reshape(n, 6).T
        return source, base, trusted.astype(bool), k, k_std, motion

    # -- shared arithmetic ---------------------------------------------------------------------
    def head_inputs(self, d, c, l_al, v, mu, sigma, source, base, trusted, k, k_std):
        return features(base, d, c, l_al, trusted, v, mu, sigma, k, k_std)

    def _finish(self, d, c, l_al, v, mu, sigma, source, base, trusted, k, k_std, motion, prev):
        x = self.head_inputs(d, c, l_al, v, mu, sigma, source, base, trusted, k, k_std)
        return self.repair(x, d, l_al, source, base, k, k_std, motion, mu, sigma, prev)

    def repair(self, x, d, l_al, source, base, k, k_std, motion, mu, sigma, prev=math.nan, first=None):
        """The head's correction, the output and the step bound from the gate's verdicts.

        ``prev`` is the output before the first row; ``first`` marks rows that start a fresh
        run (concatenated segments). Returns the ``FusedSample`` fields as arrays, in order.
        """
        tau = self.config.gate.tau_m
        delta = np.clip(self.head(x), -tau, tau) if len(x) else np.zeros(0)
        passed = source == DEPTH
        delta = np.where(corrected(source), delta, 0.0)
        d_rep = np.clip(base + delta, 0.0, MAX_RANGE_M)  # NaN stays NaN: no target
        d_fused = np.where(passed, d, d_rep)
        d_fused = bounded(d_fused, motion, self.config.step_bound_m, prev, first, free=passed)
        n = len(d_fused)
        return (d_fused, (~passed).astype(float), d_rep, np.abs(d - l_al), np.abs(delta),
                np.abs(d_fused - l_al), np.broadcast_to(mu, n), np.broadcast_to(sigma, n), k, k_std,
                np.asarray(source, float))
