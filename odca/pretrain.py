"""Pretrains the project's own small Chronos-2 checkpoint from scratch on synthetic series.

The Hugging Face hub is unreachable on the build machines, so the prior is a tiny model of
the Chronos-2 architecture (``chronos.chronos2.Chronos2Model``), randomly initialised and
trained with ``Chronos2Pipeline.fit`` on :mod:`racf.odca.synthetic` series. It is *not*
Amazon's ``amazon/chronos-2`` weights; its model card says how it was made and scored.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from racf.odca.prior import Chronos2Prior, LastValuePrior
from racf.odca.synthetic import synthetic_series

__all__ = ["TINY_CONFIG", "pretrain_prior", "score_prior", "write_scores"]

HORIZON = 16
#: The tiny architecture: ~0.3M parameters, ~1.2 MB of float32 weights.
TINY_CONFIG = dict(d_model=96, d_kv=24, d_ff=192, num_layers=2, num_heads=4, dropout_rate=0.0)
CHRONOS_CONFIG = dict(context_length=64, input_patch_size=8, output_patch_size=8, input_patch_stride=8,
                      quantiles=[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9], use_reg_token=True,
                      use_arcsinh=True, max_output_patches=2)


def pretrain_prior(out_dir: Path, steps: int = 3000, n_series: int = 6000, seed: int = 0,
                   sim_series: list[np.ndarray] | None = None) -> dict:
    """Trains, saves to ``out_dir`` with a model card, and returns the scores."""
    import torch
    from chronos.chronos2 import Chronos2Model, Chronos2Pipeline
    from chronos.chronos2.config import Chronos2CoreConfig

    torch.manual_seed(seed)
    config = Chronos2CoreConfig(**TINY_CONFIG, chronos_config=dict(CHRONOS_CONFIG))
    pipeline = Chronos2Pipeline(Chronos2Model(config))
    train = synthetic_series(n_series, seed)
    with tempfile.TemporaryDirectory() as tmp:
        fitted = pipeline.fit(train, prediction_length=HORIZON, context_length=CHRONOS_CONFIG["context_length"],
                              learning_rate=2e-3, num_steps=steps, batch_size=64, output_dir=tmp,
                              remove_printer_callback=True, seed=seed)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fitted.save_pretrained(out_dir)
    n_params = sum(p.numel() for p in fitted.model.parameters())
    meta = {"parameters": int(n_params), "steps": steps, "n_series": n_series, "seed": seed,
            "config": TINY_CONFIG, "chronos_config": CHRONOS_CONFIG}
    return write_scores(out_dir, meta, sim_series)


def write_scores(out_dir: Path, meta: dict, sim_series: list[np.ndarray] | None = None) -> dict:
    """Scores the checkpoint in ``out_dir`` and writes ``racf_prior.json`` and ``MODEL_CARD.md``."""
    prior = Chronos2Prior(out_dir)
    scores = {"synthetic_held_out": score_prior(prior, synthetic_series(400, meta["seed"] + 1))}
    if sim_series:
        scores["simulator"] = score_prior(prior, sim_series)
    meta = {**meta, "scores": scores, "size_bytes": int(sum(p.stat().st_size for p in Path(out_dir).iterdir()
                                                           if p.is_file() and p.suffix != ".md"))}
    (Path(out_dir) / "racf_prior.json").write_text(json.dumps(meta, indent=1))
    _write_card(Path(out_dir) / "MODEL_CARD.md", meta)
    return meta


def score_prior(prior, series: list[np.ndarray], stride: int = 16) -> dict:
    """H = 16 MAE of the prior and of the last-value forecast on every full window; their ratio."""
    w = prior.context_length
    ctx, fut = [], []
    for s in series:
        for end in range(w, len(s) - HORIZON + 1, stride):
            target = s[end:end + HORIZON]
            if np.isfinite(target).all() and np.isfinite(s[end - w:end]).any():
                ctx.append(s[end - w:end])
                fut.append(target)
    if not ctx:
        return {"n_windows": 0}
    ctx_a, fut_a = np.asarray(ctx, float), np.asarray(fut, float)
    mean, _ = prior.forecast(ctx_a, HORIZON)
    naive, _ = LastValuePrior(w).forecast(ctx_a, HORIZON)
    mae, mae_naive = float(np.nanmean(np.abs(mean - fut_a))), float(np.nanmean(np.abs(naive - fut_a)))
    return {"n_windows": len(ctx), "mae": mae, "mae_last_value": mae_naive, "mae_ratio": mae / mae_naive}


def _write_card(path: Path, meta: dict) -> None:
    s = meta["scores"]
    lines = [f"| {name} | {v['n_windows']} | {v['mae']:.4f} | {v['mae_last_value']:.4f} | {v['mae_ratio']:.3f} |"
             for name, v in s.items() if v.get("n_windows")]
    path.write_text(f"""# chronos2-racf-tiny

**What it is.** A small model of the Chronos-2 architecture (`chronos.chronos2.Chronos2Model`,
{meta['parameters']:,} parameters, {meta['size_bytes'] / 1e6:.2f} MB), made by the racf project. It is
**not** Amazon's `amazon/chronos-2` weights, and it is much smaller and weaker than them. It
exists so the testbed runs where the Hugging Face hub is unreachable. `Chronos2Prior("amazon/chronos-2")`
loads the real model for users who can reach the hub.

**How it was made.** `racf odca pretrain-prior --steps {meta['steps']} --seed {meta['seed']}`: random
initialisation, then `Chronos2Pipeline.fit` for {meta['steps']} steps (batch 64, learning rate 2e-3)
on {meta['n_series']} synthetic series (`odca/synthetic.py`: kinematic approach curves with depth-like
noise and dropouts, kernel-synth style sums of smooth/periodic/trend parts, steps, AR(1)).
Architecture: {json.dumps(meta['config'])}; forecasting: {json.dumps(meta['chronos_config'])}.
No real or simulator data was used for training.

**How it scores** (H = 16 mean absolute error on held-out windows, against the last-value forecast):

| series | windows | MAE | MAE last value | ratio |
|---|---|---|---|---|
{chr(10).join(lines)}

**Intended use.** The frozen temporal prior of ODCA in the racf testbed. Not for forecasting
anything that matters.
""")
