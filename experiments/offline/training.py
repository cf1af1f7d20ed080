"""ODCA checkpoints from a collected dataset: ``racf odca train`` and ``racf odca pretrain-prior``."""

from __future__ import annotations

import json
from pathlib import Path

from racf.experiments.data.dataset import COLLECTION_FILE, load_dataset
from racf.provenance import atomic_write

__all__ = ["train_checkpoint", "pretrain_checkpoint"]


def train_checkpoint(dataset: Path, out: Path, split: str = "by_series", epochs: int = 800, seed: int = 0) -> dict:
    """Fits the alignment, the delta head and the gate on ``dataset``'s train split (the shipped
    prior frozen), saves the checkpoint and ``train_report.json`` to ``out``; returns the report."""
    from racf.odca.prior import Chronos2Prior
    from racf.odca.train import train_odca

    model, report = train_odca(load_dataset(dataset, split=split), Chronos2Prior(), epochs=epochs, seed=seed)
    # What it was trained on: the dataset's making (sensor profile, sign geometry, drives, seed) and the split.
    made = Path(dataset) / COLLECTION_FILE
    report = {"dataset": {"path": str(dataset), "split": split, "epochs": epochs, "seed": seed,
                          **(json.loads(made.read_text()) if made.exists() else {})}, **report}
    model.save(out)
    atomic_write(Path(out) / "train_report.json", json.dumps(report, indent=1, allow_nan=False))
    return report


def pretrain_checkpoint(out: Path, steps: int, series: int, seed: int, dataset: Path | None = None) -> dict:
    """Pretrains the small Chronos-2 prior on synthetic series and writes it to ``out``. Where
    ``dataset`` holds a collected dataset, its test split's d_clean series are scored too."""
    import torch

    from racf.odca.pretrain import pretrain_prior

    torch.manual_seed(seed)
    sim_series = None
    if dataset is not None and (Path(dataset) / "dataset.parquet").exists():
        sim_series = load_dataset(dataset).series("d_clean", "test")
    return pretrain_prior(out, steps=steps, n_series=series, seed=seed, sim_series=sim_series)
