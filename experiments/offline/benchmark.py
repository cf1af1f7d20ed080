"""The offline repair benchmark: every method on both splits under every preset (``racf bench offline``).

Per split (by series; leave one target out) the benchmark trains what needs training on
that split's train series (ODCA's head and gate, the four neuralforecast models; cached by
what made them, so a rerun only rescores), corrupts the test series with each preset
(fixed seeds per series), runs every method causally and scores it (``docs/protocol.md``).
It adds the loss ablation (ODCA's head retrained per objective), BD / RGR, the complexity
figures and the clean pass-through, and writes ``results.json``, Markdown / CSV tables and
PNG figures (:mod:`racf.experiments.offline.report`).
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from racf.experiments.data.dataset import SPLITS, QCarDataset, load_dataset
from racf.experiments.offline.ablation import ABLATION, run_ablation
from racf.experiments.offline.forecasters import NF_MODELS, ChronosForecaster, NFSettings, train_nf, training_frame
from racf.experiments.offline.methods import (FORECASTERS, estimator_estimate, forecast_at, lidar_estimate,
                                              offline_estimators, split_arrays, table_order)
from racf.experiments.offline.metrics import bounded_degradation, resilience_gain
from racf.provenance import code_version
from racf.experiments.offline.scoring import (bootstrap_rmse_draws, diagnostic_scores, error_sources, horizon_scores,
                                         mean_over_draws, recovery_scores, series_sse)

__all__ = ["BenchConfig", "ABLATION", "load_splits", "run_benchmark", "PRESETS", "frame_hash"]

PRESETS = ("weak", "mid", "strong")
#: The source a benchmark result depends on: the methods (ODCA, the EKF), the corruption and the scoring.
BENCH_CODE = ("racf.odca", "racf.controllers", "racf.experiments.data", "racf.experiments.offline")


@dataclass(frozen=True)
class BenchConfig:
    """What ``racf bench offline`` runs.

    Attributes:
        data: the dataset folder (``racf collect``).
        out: results folder.
        splits: split schemes to run.
        presets: corruption presets.
        seed: training seeds (ODCA head, neuralforecast models) and the bootstrap's.
        draws: corruption draws per preset (each series' draw k is seeded by its drive's seed,
            the preset and k); a score is the mean over them.
        odca_epochs: full-batch epochs of ODCA's head.
        nf: the neuralforecast baselines' settings.
        ablation: run the loss ablation (five head trainings on the first split).
        bootstrap: resamples of test series for the RMSE intervals.
        quick: a few series per split and short training (what the tests run).
        cache: trained-model cache (default ``out/cache``).
    """

    data: Path = Path("data/qcar2")
    out: Path = Path("outputs/bench")
    splits: tuple[str, ...] = SPLITS
    presets: tuple[str, ...] = PRESETS
    seed: int = 0
    draws: int = 5
    odca_epochs: int = 800
    nf: NFSettings = field(default_factory=NFSettings)
    ablation: bool = True
    bootstrap: int = 1000
    quick: bool = False
    cache: Path | None = None

    def __post_init__(self) -> None:
        bad = [s for s in self.splits if s not in SPLITS]
        if not self.splits or bad:
            raise ValueError(f"splits must be a non-empty subset of {SPLITS}, got {list(self.splits)}")
        bad = [p for p in self.presets if p not in PRESETS]
        if not self.presets or bad:
            raise ValueError(f"presets must be a non-empty subset of {PRESETS}, got {list(self.presets)}")
        if not (isinstance(self.draws, int) and 1 <= self.draws <= 100):
            raise ValueError(f"draws must be an integer in [1, 100] (the protocol asks for >= 5), got {self.draws!r}")
        if self.odca_epochs < 1 or self.bootstrap < 0:
            raise ValueError(f"odca_epochs must be >= 1 and bootstrap >= 0, got {self.odca_epochs}, {self.bootstrap}")

    @classmethod
    def quick_config(cls, **overrides) -> "BenchConfig":
        """A few series, short training: minutes, not a result to quote."""
        base = dict(odca_epochs=40, nf=NFSettings(max_steps=15), bootstrap=100, quick=True, draws=2)
        return cls(**{**base, **overrides})

    @classmethod
    def from_options(cls, quick: bool = False, max_steps: int | None = None, epochs: int | None = None,
                     **fields) -> "BenchConfig":
        """The full (or ``quick``) configuration with the command line's overrides: the
        neuralforecast baselines' optimiser steps and ODCA's epochs, where given."""
        cfg = cls.quick_config(**fields) if quick else cls(**fields)
        if max_steps is not None:
            cfg = replace(cfg, nf=replace(cfg.nf, max_steps=max_steps))
        if epochs is not None:
            cfg = replace(cfg, odca_epochs=epochs)
        return cfg

    @property
    def cache_dir(self) -> Path:
        return Path(self.cache) if self.cache is not None else Path(self.out) / "cache"

    def to_json(self) -> dict:
        raw = asdict(self)
        return {**raw, "data": str(self.data), "out": str(self.out), "cache": str(self.cache_dir)}


#: Test / train / val series per split in quick mode.
_QUICK = {"train": 4, "val": 1, "test": 2}


def _quick(ds: QCarDataset) -> QCarDataset:
    split = {k: ds.split[k][:_QUICK[k]] for k in ("train", "val", "test")}
    keep = ds.frame["series_id"].isin(sum(split.values(), []))
    return QCarDataset(ds.frame[keep].reset_index(drop=True), split, ds.path, ds.scheme, ds.splits)


#: The dataset columns a method or a training reads (the hash of a split covers these).
_USED = ["series_id", "drive_seed", "t", "slot", "d_clean", "c_clean", "d_true", "lidar", "speed", "yaw_rate",
         "bearing"]


def frame_hash(*frames: pd.DataFrame) -> str:
    """A short hash of the columns the benchmark reads, so a new dataset is a new key."""
    digest = hashlib.sha256()
    for frame in frames:
        digest.update(pd.util.hash_pandas_object(frame[_USED], index=False).to_numpy().tobytes())
    return digest.hexdigest()[:16]


#: The prior's features on the current split's train/val series, shared by the ablation's heads.
_PREPARED: dict = {}


def _trained_odca(ds: QCarDataset, prior, cfg: BenchConfig, weights: dict, tag: str, kinematics: dict | None = None):
    """ODCA trained on the split's train series with these loss weights (and kinematic branch
    settings); cached by what made it."""
    from racf.odca import ODCA
    from racf.odca.losses import LossWeights
    from racf.odca.prior import SHIPPED_PRIOR
    from racf.odca.train import clean_series, fit, initial_model, prepare_clean, prepare_split

    code = code_version("racf.odca", "racf.experiments.data")
    key = hashlib.sha256(json.dumps({"data": frame_hash(ds.clean("train"), ds.clean("val")), "weights": weights,
                                     "kinematics": kinematics or {},
                                     "epochs": cfg.odca_epochs, "seed": cfg.seed, "code": code,
                                     "prior": code_version(str(SHIPPED_PRIOR))},
                                    sort_keys=True).encode()).hexdigest()[:16]
    folder = cfg.cache_dir / f"odca-{tag}-{key}"
    if (folder / "report.json").exists():
        return ODCA.load(folder, prior=prior), json.loads((folder / "report.json").read_text())
    model = initial_model(ds, prior)
    model.config = replace(model.config, kinematics=replace(model.config.kinematics, **(kinematics or {})))
    cache = _PREPARED
    data_key = (frame_hash(ds.clean("train"), ds.clean("val")), id(prior))
    if cache.get("key") != data_key:  # the prior's features on train/val, shared by the ablation's heads
        cache.clear()
        cache.update(key=data_key, train=prepare_split(model, ds, "train"), val=prepare_split(model, ds, "val"),
                     clean=prepare_clean(model, clean_series(ds)))
    t0 = time.perf_counter()
    report = fit(model, cache["train"], cache["val"], epochs=cfg.odca_epochs, seed=cfg.seed,
                 weights=LossWeights(**weights), progress=False, clean=cache["clean"])
    report["train_s"] = time.perf_counter() - t0
    model.save(folder)
    (folder / "report.json").write_text(json.dumps(report, indent=1, allow_nan=False))
    return model, report


def _score_split(ds: QCarDataset, preset: str, odca_model, forecasters: dict, cfg: BenchConfig
                 ) -> tuple[dict, dict]:
    """All methods on one split's test series under one preset, over ``cfg.draws`` corruption draws:
    (scores per method, traces of draw 0 for figures).

    A score is the mean over draws (counts are summed); ``rmse_draws`` lists each draw's RMSE
    and ``rmse_ci`` resamples test drives and draws together.
    """
    series = list(ds.split["test"])
    per_draw: dict[str, list] = {}
    sse: dict[str, list] = {}
    sources: dict[str, list] = {}
    traces = {}
    for draw in range(cfg.draws):
        frame = ds.corrupted(preset, "test", draw)
        a = split_arrays(frame, odca_model.config.alignment)
        estimates, horizon = _estimates(frame, a, odca_model, forecasters)
        for name in table_order(estimates):
            est = estimates[name]
            per_draw.setdefault(name, []).append({**recovery_scores(est, a), **horizon.get(name, {}),
                                                  **diagnostic_scores(est, a)})
            sse.setdefault(name, []).append(series_sse(est, a, series))
            sources.setdefault(name, []).append(error_sources(est, a))
        if draw == 0:
            traces = {"frame": frame[["series_id", "t", "d_clean", "d_meas", "label"]].assign(
                **{f"est_{k}": v for k, v in estimates.items()})}
    scores = {}
    for name, rows in per_draw.items():
        row = mean_over_draws(rows)
        row["n_draws"], row["n_series"] = cfg.draws, len(series)
        row["rmse_draws"] = [r["rmse"] for r in rows]
        errors, counts = (np.stack([pair[i] for pair in sse[name]], axis=1) for i in (0, 1))
        row["rmse_ci"] = bootstrap_rmse_draws(errors, counts, cfg.bootstrap, cfg.seed)
        row["error_sources"] = _pooled_sources(sources[name])
        scores[name] = row
    return scores, traces


def _estimates(frame: pd.DataFrame, a, odca_model, forecasters: dict) -> tuple[dict, dict]:
    """Every method's estimate on one corrupted frame, and the forecasters' horizon scores.

    Every registered estimator runs as the car runs it (``odca`` with the split's trained
    model); the LiDAR reference and the forecasters are offline-only."""
    origins = np.flatnonzero(a.scored)
    estimates = {"lidar": lidar_estimate(a)}
    for name in offline_estimators():
        estimates[name] = estimator_estimate(_bench_estimator(name, odca_model), a, frame)
    horizon = {}
    for name, forecaster in forecasters.items():
        one_step, paths = forecast_at(forecaster, a, origins, odca_model.config.context_length,
                                      odca_model.config.horizon)
        est = np.full(len(a), np.nan)
        est[origins] = one_step
        estimates[name] = est
        horizon[name] = horizon_scores(origins, paths, a)
    return estimates, horizon


def _bench_estimator(name: str, odca_model):
    """The estimator ``name`` as the car builds it; ODCA with this split's trained model."""
    from racf.experiments.car.estimators import ODCAEstimator, make_estimator

    return ODCAEstimator.of(odca_model) if name == "odca" else make_estimator(name)


def _pooled_sources(per_draw: list[dict]) -> dict:
    """Error sources summed over draws (N and SSE), with the pooled RMSE."""
    out = {}
    for key in per_draw[0]:
        n = sum(d[key]["n"] for d in per_draw)
        total = sum(d[key]["sse"] for d in per_draw)
        out[key] = {"n": n, "sse": total, "rmse": float(np.sqrt(total / n)) if n else None}
    return out


def _complexity(odca_report: dict, forecasters: dict, prior_params: int) -> dict:
    out = {"raw": {"trainable": 0, "total": 0}, "lidar": {"trainable": 0, "total": 2},
           "ekf": {"trainable": 0, "total": 6},
           "odca": {"trainable": int(odca_report["head_parameters"]),
                    "total": int(odca_report["head_parameters"]) + prior_params + 2 + 4}}
    for name, f in forecasters.items():
        n = f.n_parameters
        out[name] = {"trainable": 0 if name == "chronos" else n, "total": n}
    return out


def load_splits(cfg: BenchConfig) -> dict[str, QCarDataset]:
    """The dataset under each split scheme (a quick subset with ``cfg.quick``); a clear error if one cannot serve."""
    datasets = {}
    for split in cfg.splits:
        ds = load_dataset(cfg.data, split=split)
        ds = _quick(ds) if cfg.quick else ds
        empty = [part for part in ("train", "val", "test") if not ds.split[part]]
        if empty:
            raise ValueError(f"the {split} split of {cfg.data} has no {' or '.join(empty)} series; "
                             "the benchmark needs all three (collect more drives)")
        datasets[split] = ds
    return datasets


class _MemoPrior:
    """A prior that remembers its forecasts by their input. The ablation's heads share the prior
    and score the same corrupted frames, so each context is forecast once; the prior is a pure
    function of its input, so the numbers are the ones it would give again."""

    def __init__(self, prior) -> None:
        self._prior, self._memo = prior, {}

    def __getattr__(self, name: str):
        return getattr(self._prior, name)

    def forecast(self, context: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
        context = np.ascontiguousarray(context, dtype=float)
        key = (context.shape, horizon, hashlib.sha256(context.tobytes()).digest())
        if key not in self._memo:
            self._memo[key] = self._prior.forecast(context, horizon)
        mean, std = self._memo[key]
        return mean.copy(), std.copy()


def run_benchmark(cfg: BenchConfig, progress: bool = True, datasets: dict[str, QCarDataset] | None = None) -> dict:
    """Runs the benchmark and returns the results object (also written by :func:`report.write_report`)."""
    from tqdm import tqdm

    from racf.odca.prior import SHIPPED_PRIOR, Chronos2Prior
    from racf.odca.train import pass_through

    t0 = time.perf_counter()
    datasets = datasets or load_splits(cfg)
    n_stages = len(cfg.splits) * (2 + len(NF_MODELS) + len(cfg.presets)) + (len(ABLATION) - 1 if cfg.ablation else 0)
    bar = tqdm(total=n_stages, desc="bench", unit="stage", disable=not progress)

    def stage(text: str) -> None:
        bar.set_postfix_str(text)

    prior = _MemoPrior(Chronos2Prior())
    chronos = ChronosForecaster(horizon=cfg.nf.horizon)
    results: dict = {"config": cfg.to_json()}
    traces: dict = {}
    complexity: dict = {}
    ablation: list = []
    for split in cfg.splits:
        ds = datasets[split]
        stage(f"{split}: ODCA head")
        odca_model, odca_report = _trained_odca(ds, prior, cfg, ABLATION["full"]["loss_weights"], split)
        bar.update()
        forecasters = {"chronos": chronos}
        train = training_frame(ds.clean("train"))
        for name in NF_MODELS:
            stage(f"{split}: train {name}")
            forecasters[name] = train_nf(name, train, cfg.nf, cfg.cache_dir)
            bar.update()
        forecasters = {k: forecasters[k] for k in FORECASTERS}
        per_preset = {}
        for preset in cfg.presets:
            stage(f"{split}: score {preset}")
            per_preset[preset], traces[(split, preset)] = _score_split(ds, preset, odca_model, forecasters, cfg)
            bar.update()
        stage(f"{split}: clean pass-through")
        clean = pass_through(odca_model, ds.clean("test"))
        bar.update()
        results[split] = per_preset
        results.setdefault("clean", {})[split] = clean
        results.setdefault("training", {})[split] = {
            "odca": odca_report, "n_series": {k: len(v) for k, v in ds.split.items()},
            "nf": {k: {"cache_key": f.key, "train_s": f.train_s} for k, f in forecasters.items() if k != "chronos"}}
        if split == cfg.splits[0]:
            complexity = _complexity(odca_report, forecasters, chronos.n_parameters)
            if cfg.ablation and "strong" in cfg.presets:
                ablation = run_ablation(ds, cfg.draws, per_preset["strong"]["odca"], odca_report, stage, bar,
                                        lambda weights, kinematics: _trained_odca(ds, prior, cfg, weights, "ablation",
                                                                                  kinematics))
    bar.close()
    first = cfg.splits[0]
    results["clean"]["odca_rmse_vs_input"] = results["clean"][first]["rmse_vs_input"]
    results["derived"] = {split: _derived(results[split]) for split in cfg.splits}
    if "strong" in cfg.presets:
        for name, row in complexity.items():
            row["rmse_strong"] = results[first]["strong"][name]["rmse"]
    results["complexity"] = complexity
    results["ablation"] = ablation
    frames = [datasets[s].frame for s in cfg.splits[:1]]
    results["dataset"] = {"path": str(cfg.data), "quick": cfg.quick, "sha": frame_hash(*frames),
                          "code": code_version(*BENCH_CODE), "prior": code_version(str(SHIPPED_PRIOR))}
    results["wall_s"] = time.perf_counter() - t0
    results["_traces"] = traces  # for the figures; not written to results.json
    return results


def _derived(per_preset: dict) -> dict:
    methods = next(iter(per_preset.values())).keys()
    chronos = {p: per_preset[p]["chronos"]["rmse"] for p in per_preset}
    out = {}
    for m in methods:
        rm = {p: per_preset[p][m]["rmse"] for p in per_preset}
        out[m] = {"bd": bounded_degradation(rm.get("weak"), rm.get("strong")), "rgr": resilience_gain(rm, chronos)}
    return out
