"""``racf train-detector``: trains the stop-sign segmenter on rendered views, on the CPU.

Per-pixel binary cross-entropy plus a soft Dice term, against the ground-truth face masks
pooled to the network's half resolution (a pixel's target is the share of its 2x2 block on
a face). Photometric jitter (gain, offset, per-channel tint, sensor noise) and mirror flips
widen the renderer's lighting; the learning rate follows a cosine from ``lr`` to zero.

Seeded: the weights' initialisation, the batch order and every jitter come from ``seed``;
the same seed and thread count give the same checkpoint (float tolerance across machines).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional as F

from racf.controllers.learned_detector import LearnedSignDetector, save_segmenter
from racf.controllers.segmenter_net import SegmenterConfig, SignSegmenterNet
from racf.experiments.detector.dataset import load_split
from racf.experiments.detector.evaluate import DetectionCounts, score_frame

__all__ = ["TrainConfig", "train_segmenter", "evaluate_detector_on_split"]


@dataclass(frozen=True)
class TrainConfig:
    """Training settings.

    Attributes:
        seed: initialisation, batch order and augmentation.
        epochs: passes over the training split.
        batch: views per step.
        lr: peak Adam learning rate (cosine decay to 0).
        weight_decay: AdamW's decoupled decay.
        pos_weight: weight of a face pixel in the cross-entropy (faces are a few % of pixels).
        hard_weight: weight of the frame term on each frame's highest background score.
        threads: torch CPU threads (the result depends on it at float precision only).
    """

    seed: int = 0
    epochs: int = 30
    batch: int = 16
    lr: float = 3e-3
    weight_decay: float = 1e-4
    pos_weight: float = 3.0
    hard_weight: float = 0.0
    threads: int = 2

    def __post_init__(self) -> None:
        for name, lo, hi in (("seed", 0, 2**31), ("epochs", 1, 1000), ("batch", 1, 512), ("threads", 1, 256)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
                raise ValueError(f"{name} must be an int in [{lo}, {hi}], got {value!r}")
        for name in ("lr", "pos_weight"):
            if not 0 < getattr(self, name) <= 100:
                raise ValueError(f"{name} must be in (0, 100], got {getattr(self, name)!r}")
        if not 0 <= self.hard_weight <= 100:
            raise ValueError(f"hard_weight must be in [0, 100], got {self.hard_weight!r}")
        if not 0 <= self.weight_decay < 1:
            raise ValueError(f"weight_decay must be in [0, 1), got {self.weight_decay!r}")


def _augment(x: torch.Tensor, g: torch.Generator) -> torch.Tensor:
    """Photometric jitter of a (N, 3, H, W) batch in [0, 1]."""
    n = x.shape[0]
    gain = 0.7 + 0.6 * torch.rand(n, 1, 1, 1, generator=g)
    tint = 0.92 + 0.16 * torch.rand(n, 3, 1, 1, generator=g)
    offset = (torch.rand(n, 1, 1, 1, generator=g) - 0.5) * 0.12
    noise = torch.randn(x.shape, generator=g) * (0.025 * torch.rand(n, 1, 1, 1, generator=g))
    return (x * gain * tint + offset + noise).clamp_(0.0, 1.0)


def _loss(logits: torch.Tensor, target: torch.Tensor, pos_weight: float, hard_weight: float) -> torch.Tensor:
    """Pixel terms (cross-entropy, Dice) and a frame term: the highest-scoring background cell of
    each frame (outside a cell's margin around the faces) pushed below the threshold, since one
    such cell makes a false-positive frame."""
    bce = F.binary_cross_entropy_with_logits(logits, target, pos_weight=torch.tensor(pos_weight))
    p = torch.sigmoid(logits)
    dice = 1 - (2 * (p * target).sum() + 1) / (p.sum() + target.sum() + 1)
    near_face = F.max_pool2d(target, 5, stride=1, padding=2) > 0
    background = torch.where(near_face, torch.full_like(logits, -20.0), logits)
    hard = F.relu(background.flatten(1).max(dim=1).values + 2.0).mean()
    return bce + 0.5 * dice + hard_weight * hard


def evaluate_detector_on_split(detector, data: dict[str, np.ndarray], progress: bool = False) -> DetectionCounts:
    """Recall and false-positive frames of ``detector`` over a split's views (see ``evaluate``)."""
    from tqdm import tqdm

    counts = DetectionCounts()
    for i in tqdm(range(len(data["rgb"])), desc="evaluate", unit="view", disable=not progress):
        det = detector.detect(data["rgb"][i])
        counts.add(*score_frame(det, data["mask"][i], data["mask"][i], data["faces_share"][i]))
    return counts


def train_segmenter(config: TrainConfig = TrainConfig(), data_root: Path = Path("data/detector"),
                    out_dir: Path | None = None, progress: bool = True) -> tuple[SignSegmenterNet, dict]:
    """Trains a segmenter on ``data_root``'s training split; evaluates it on the held-out split.

    Returns the network and a report (settings, losses per epoch, held-out recall and
    false-positive frames, seconds); with ``out_dir`` also writes the checkpoint there.
    """
    from tqdm import tqdm

    torch.set_num_threads(config.threads)
    torch.manual_seed(config.seed)
    g = torch.Generator().manual_seed(config.seed)
    train = load_split(data_root, "train")
    heldout = load_split(data_root, "heldout")
    images = torch.from_numpy(train["rgb"]).permute(0, 3, 1, 2)  # uint8, a view of the array
    masks = torch.from_numpy(train["mask"]).unsqueeze(1).float()
    targets = F.avg_pool2d(masks, 2)  # a half-resolution cell's share of face
    del masks
    net = SignSegmenterNet(SegmenterConfig()).to(memory_format=torch.channels_last)
    opt = torch.optim.AdamW(net.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    n = len(images)
    steps_per_epoch = n // config.batch
    total = steps_per_epoch * config.epochs
    sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda s: 0.5 * (1 + math.cos(math.pi * min(s, total) / total)))
    t0 = time.perf_counter()
    losses = []
    bar = tqdm(range(config.epochs), desc="train-detector", unit="epoch", disable=not progress)
    for _ in bar:
        net.train()
        order = torch.randperm(n, generator=g)
        running = 0.0
        for s in range(steps_per_epoch):
            idx = order[s * config.batch:(s + 1) * config.batch]
            x = images[idx].float().div_(255.0)
            y = targets[idx]
            if torch.rand(1, generator=g).item() < 0.5:  # a stop sign mirrored is a stop sign
                x, y = x.flip(-1), y.flip(-1)
            x = _augment(x, g).contiguous(memory_format=torch.channels_last)
            loss = _loss(net(x), y, config.pos_weight, config.hard_weight)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            sched.step()
            running += float(loss.detach())
        losses.append(running / max(steps_per_epoch, 1))
        bar.set_postfix(loss=f"{losses[-1]:.4f}")
    train_s = time.perf_counter() - t0
    net.eval()
    counts = evaluate_detector_on_split(LearnedSignDetector(net=net), heldout, progress=progress)
    report = {"config": asdict(config), "n_train": n, "n_heldout": len(heldout["rgb"]), "epoch_loss": losses,
              "train_s": train_s, "heldout": counts.to_dict(), "torch": torch.__version__,
              "parameters": sum(p.numel() for p in net.parameters())}
    if out_dir is not None:
        save_segmenter(net, Path(out_dir), report)
    return net, report
