"""The vehicle segmenter: the sign segmenter's network given a vehicle class, trained on racf's renders.

``racf detector train-vehicle --out OUT`` renders ``n_train`` views and ``n_heldout`` held-out ones (another
seed) with :class:`~racf.experiments.detector.vehicle_views.VehicleViews`, trains the network
with the sign segmenter's loss and photometric jitter (``racf.experiments.detector.train``), and
writes the checkpoint with its report: the held-out recall of cars by range (a car found: a
component that overlaps its mask) and the share of frames without a car where one was found.
The shipped checkpoint is ``assets/checkpoints/vehicle-segmenter``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional as F

from racf.controllers.learned_detector import save_segmenter
from racf.controllers.segmenter_net import SignSegmenterNet
from racf.controllers.vehicle_detector import LearnedVehicleDetector
from racf.experiments.detector.train import fit_segmenter

__all__ = ["VehicleTrainConfig", "render_views", "train_vehicle_segmenter", "heldout_report", "RANGE_BINS_M"]

#: The held-out recall's range bins, m.
RANGE_BINS_M = ((0.3, 1.0), (1.0, 2.0), (2.0, 3.0))


@dataclass(frozen=True)
class VehicleTrainConfig:
    """How the vehicle segmenter is made (its seeds are the split's and the training's)."""

    seed: int = 0
    n_train: int = 4000
    n_heldout: int = 800
    epochs: int = 12
    batch: int = 16
    lr: float = 3e-3
    weight_decay: float = 1e-4
    pos_weight: float = 3.0
    hard_weight: float = 0.05
    threads: int = 2

    def __post_init__(self) -> None:
        for name, lo, hi in (("seed", 0, 2**31), ("n_train", 16, 10**6), ("n_heldout", 1, 10**6), ("epochs", 1, 1000),
                             ("batch", 1, 512), ("threads", 1, 256)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
                raise ValueError(f"{name} must be an int in [{lo}, {hi}], got {value!r}")


def render_views(n: int, seed: int, progress: bool = False) -> dict[str, np.ndarray]:
    """``n`` views: ``rgb`` (n, H, W, 3) uint8, ``mask`` (n, H, W) bool, ``range_m`` (n,) (NaN: no car)."""
    from tqdm import tqdm

    from racf.experiments.detector.vehicle_views import VehicleViews

    views, rng = VehicleViews(), np.random.default_rng(seed)
    try:
        rows = [views.draw(rng) for _ in tqdm(range(n), desc="vehicle views", unit="view", disable=not progress)]
    finally:
        views.close()
    return {"rgb": np.stack([r[0] for r in rows]), "mask": np.stack([r[1] for r in rows]),
            "range_m": np.array([r[2] for r in rows])}


def heldout_report(detector: LearnedVehicleDetector, data: dict[str, np.ndarray]) -> dict:
    """Recall by range bin (a car with at least 20 visible pixels counts) and the false-positive
    share over frames without a visible car."""
    found, fp, n_empty = {b: [0, 0] for b in RANGE_BINS_M}, 0, 0
    for rgb, mask, r in zip(data["rgb"], data["mask"], data["range_m"]):
        candidates = detector.candidates(rgb)
        if mask.sum() < 20:
            n_empty += 1
            fp += bool(candidates)
            continue
        for lo, hi in RANGE_BINS_M:
            if lo <= r < hi:
                found[(lo, hi)][1] += 1
                found[(lo, hi)][0] += any((c.mask & mask).any() for c in candidates)
    return {"recall": {f"{lo}-{hi} m": {"found": k, "n": n, "share": (k / n if n else None)}
                       for (lo, hi), (k, n) in found.items()},
            "false_positive": {"frames": fp, "n": n_empty, "share": (fp / n_empty if n_empty else None)}}


def train_vehicle_segmenter(config: VehicleTrainConfig = VehicleTrainConfig(), out_dir: Path | None = None,
                            progress: bool = True) -> tuple[SignSegmenterNet, dict]:
    """Renders the views, trains the network and evaluates it on the held-out views."""
    torch.set_num_threads(config.threads)
    torch.manual_seed(config.seed)
    g = torch.Generator().manual_seed(config.seed)
    train = render_views(config.n_train, config.seed, progress)
    heldout = render_views(config.n_heldout, config.seed + 1_000_003, progress)
    images = torch.from_numpy(train["rgb"]).permute(0, 3, 1, 2)
    targets = F.avg_pool2d(torch.from_numpy(train["mask"]).unsqueeze(1).float(), 2)
    net, losses, train_s = fit_segmenter(images, targets, config, g, progress, "train vehicle segmenter")
    report = {"config": asdict(config), "epoch_loss": losses, "train_s": train_s,
              "heldout": heldout_report(LearnedVehicleDetector(net=net), heldout), "torch": torch.__version__,
              "parameters": sum(p.numel() for p in net.parameters())}
    if out_dir is not None:
        save_segmenter(net, Path(out_dir), report)
    return net, report

