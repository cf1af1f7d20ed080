"""Training the delta head, calibrating the alignment and the gate, and scoring the result.

Data: long-format frames of corrupted series (``series_id``, ``d_meas``, ``c_meas``,
``lidar``, ``speed``, ``label``, and ``d_clean`` for scoring only). The head never sees
d_clean or d_true: the four losses use the measurement, the LiDAR and the speed.

1. Alignment: Huber regression of d_clean on the LiDAR over confident clean samples of the
   training split (the paper's "initial clean calibration run").
2. Head: full-batch Adam on the four losses over the train split corrupted with every
   preset (each series with its fixed seed).
3. Gate: tau_low among the 95th / 99th / 99.5th percentiles of the residual on
   unattacked validation steps, tau_high and gamma by grid search for the lowest
   validation RMSE against d_clean.
"""

from __future__ import annotations

from dataclasses import asdict, replace

import numpy as np
import pandas as pd

from odca.align import fit_alignment
from odca.features import base_distance, features
from odca.gate import GateConfig
from odca.head import HeadWeights, head_parameters, make_head
from odca.losses import LossWeights, odca_losses
from odca.online import ODCA, ODCAConfig

__all__ = ["prepare", "train_head", "calibrate_gate", "score", "train_odca"]


def prepare(model: ODCA, frame: pd.DataFrame) -> dict[str, np.ndarray]:
    """Per-step arrays for training/scoring: inputs, prior features, features X, base, flags."""
    parts = []
    for sid, s in frame.groupby("series_id", sort=False):
        d, c, l, v, mu, sigma, d_prev, hold = model.series_inputs(s["d_meas"], s["c_meas"], s["lidar"], s["speed"])
        l_al = model.config.alignment(l)
        x = features(d, c, l_al, v, mu, sigma, d_prev, hold, model.config.dt)
        # The LiDAR is trusted where it agrees with the prior (or there is no prior yet).
        trusted = np.isfinite(l_al) & (~np.isfinite(mu) | (np.abs(l_al - mu) <= 0.3 + 2 * np.nan_to_num(sigma)))
        parts.append({"x": x, "base": base_distance(d, mu, l_al, hold), "hold": hold, "d": d, "c": c,
                      "l_al": l_al, "v": v,
                      "trusted": trusted,
                      "label": s["label"].to_numpy(), "d_clean": s["d_clean"].to_numpy(float),
                      "first": np.arange(len(d)) == 0})
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def train_head(data: dict[str, np.ndarray], tau_low: float, dt: float = 0.02, epochs: int = 800, lr: float = 3e-3,
               seed: int = 0, weights: LossWeights | None = None, progress: bool = True):
    """Trains the head; returns (HeadWeights, history list of per-epoch loss dicts)."""
    import torch
    from tqdm import tqdm

    torch.manual_seed(seed)
    weights = weights or LossWeights()
    head = make_head()
    t = {k: torch.tensor(np.nan_to_num(v, nan=0.0), dtype=torch.float32) for k, v in data.items()
         if k in ("x", "base", "d", "c", "l_al", "v")}
    clean = torch.tensor((data["label"] == 0) & (data["c"] >= 0.5) & np.isfinite(data["d"]))
    valid_pair = torch.tensor(~data["first"])
    trusted = torch.tensor(data["trusted"])
    opt = torch.optim.Adam(head.parameters(), lr=lr)
    history = []
    for _ in tqdm(range(epochs), desc=f"train delta head ({head_parameters(head)} params)", unit="epoch",
                  disable=not progress):
        opt.zero_grad()
        total, parts = odca_losses(head(t["x"]), t["base"], t["d"], t["c"], t["l_al"], t["v"], clean, valid_pair,
                                   dt, tau_low, weights, trusted)
        total.backward()
        opt.step()
        history.append({"total": float(total), **{k: float(v) for k, v in parts.items()}})
    return HeadWeights.from_module(head), history


def _fused(model: ODCA, data: dict[str, np.ndarray]) -> np.ndarray:
    """The module's own output from the prepared features (no second copy of the fusion)."""
    return model.repair(data["x"], data["d"], data["l_al"], data["base"], data["hold"])[0]


def score(model: ODCA, data: dict[str, np.ndarray]) -> dict[str, float]:
    """RMSE/MAE against d_clean of ODCA's output and of the raw measurement (last valid value held)."""
    ok = np.isfinite(data["d_clean"])
    fused = _fused(model, data)
    raw = pd.Series(data["d"]).ffill().fillna(0.0).to_numpy()
    err, err_raw = (fused - data["d_clean"])[ok], (raw - data["d_clean"])[ok]
    return {"rmse": float(np.sqrt(np.mean(err**2))), "mae": float(np.mean(np.abs(err))),
            "rmse_raw": float(np.sqrt(np.mean(err_raw**2))), "mae_raw": float(np.mean(np.abs(err_raw))),
            "n": int(ok.sum())}


def calibrate_gate(model: ODCA, val: dict[str, np.ndarray]) -> GateConfig:
    """tau_low among high percentiles of unattacked residuals, (tau_high, gamma) by grid search on validation RMSE."""
    r = np.abs(val["d"] - val["l_al"])
    clean_r = r[(val["label"] == 0) & np.isfinite(r)]
    best = None
    for pct in (95.0, 99.0, 99.5):
        tau_low = float(np.percentile(clean_r, pct)) if clean_r.size else 0.1
        for span in (0.05, 0.1, 0.2, 0.3, 0.5):
            for gamma in (0.5, 1.0, 2.0):
                gate = GateConfig(tau_low, tau_low + span, gamma)
                model.config = replace(model.config, gate=gate)
                rmse = score(model, val)["rmse"]
                if best is None or rmse < best[0]:
                    best = (rmse, gate)
    model.config = replace(model.config, gate=best[1])
    return best[1]


def train_odca(dataset, prior, epochs: int = 800, seed: int = 0, presets=("weak", "mid", "strong"),
               progress: bool = True) -> tuple[ODCA, dict]:
    """The whole recipe on a ``QCarDataset``; returns the trained ODCA and a report."""
    train_clean = dataset.clean("train")
    ok = np.isfinite(train_clean["d_clean"]) & np.isfinite(train_clean["lidar"])
    alignment = fit_alignment(train_clean.loc[ok, "d_clean"].to_numpy(), train_clean.loc[ok, "lidar"].to_numpy(),
                              train_clean.loc[ok, "c_clean"].to_numpy())
    config = ODCAConfig(alignment=alignment)
    placeholder = HeadWeights.from_module(make_head())
    model = ODCA(config, placeholder, prior)

    def frames(split):
        return pd.concat([dataset.corrupted(p, split).assign(series_id=lambda f, p=p: f["series_id"] + "|" + p)
                          for p in presets], ignore_index=True)

    train = prepare(model, frames("train"))
    val = prepare(model, frames("val"))
    clean_r = np.abs(train["d"] - train["l_al"])[(train["label"] == 0) & np.isfinite(train["d"] - train["l_al"])]
    tau_low = float(np.percentile(clean_r, 95))
    head, history = train_head(train, tau_low, config.dt, epochs=epochs, seed=seed, progress=progress)
    model.head = head
    gate = calibrate_gate(model, val)
    report = {"alignment": asdict(alignment), "gate": asdict(gate), "head_parameters": head.n_parameters,
              "final_losses": history[-1], "epochs": epochs, "seed": seed, "train_steps": int(len(train["d"])),
              "test": {}}
    for preset in presets:
        report["test"][preset] = score(model, prepare(model, dataset.corrupted(preset, "test")))
    return model, report
