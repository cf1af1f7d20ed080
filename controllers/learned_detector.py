"""Stop-sign detection by a learned segmenter (the paper detects the sign with YOLOv8-seg).

A small convolutional network (:class:`~racf.controllers.segmenter_net.SignSegmenterNet`) scores
every pixel; the pixels above ``threshold`` form connected components, and each component
large enough is a candidate whose confidence is its mean score. Same interface as the
colour-and-shape detector (``detect`` / ``candidates`` -> :class:`~racf.controllers.detector.Detection`),
so perception, the referee and the benchmarks take either by name (``racf.controllers.detectors``).

The network's weights are the project's own checkpoint (``assets/checkpoints/sign-segmenter``),
trained on the simulator's frames by ``racf detector train``; nothing is downloaded.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import torch

from racf.controllers.components import sparse_components
from racf.controllers.detector import BlobDetector, Detection, check_rgb
from racf.controllers.segmenter_net import SegmenterConfig, SignSegmenterNet
from racf.assets import asset_path

__all__ = ["LearnedDetectorConfig", "LearnedSignDetector", "SHIPPED_SEGMENTER", "load_segmenter", "save_segmenter"]

#: The shipped checkpoint's directory: ``model.pt`` (state dict) and ``segmenter.json``.
SHIPPED_SEGMENTER = asset_path("checkpoints", "sign-segmenter")


@dataclass(frozen=True)
class LearnedDetectorConfig:
    """Post-processing of the segmenter's scores.

    Attributes:
        threshold: a pixel belongs to a sign when its score (a probability) exceeds this.
        min_area_px: smallest component reported, pixels of the full frame.
        min_confidence: components whose mean score is below this are not reported.
    """

    threshold: float = 0.5
    min_area_px: int = 8
    min_confidence: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 < self.threshold < 1.0:
            raise ValueError(f"threshold must be in (0, 1), got {self.threshold!r}")
        if isinstance(self.min_area_px, bool) or not isinstance(self.min_area_px, int) or self.min_area_px < 1:
            raise ValueError(f"min_area_px must be an int >= 1, got {self.min_area_px!r}")
        if not 0.0 <= self.min_confidence <= 1.0:
            raise ValueError(f"min_confidence must be in [0, 1], got {self.min_confidence!r}")


def save_segmenter(net: SignSegmenterNet, directory: Path, report: dict | None = None) -> None:
    """Writes ``net`` as a checkpoint directory (weights, architecture, and what trained it)."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    torch.save(net.state_dict(), directory / "model.pt")
    meta = {"architecture": net.config.__dict__, "report": report or {}}
    (directory / "segmenter.json").write_text(json.dumps(meta, indent=2, sort_keys=True) + "\n")


def load_segmenter(directory: Path = SHIPPED_SEGMENTER) -> SignSegmenterNet:
    """The network of a checkpoint directory, in eval mode; FileNotFoundError says how to make one."""
    directory = Path(directory)
    weights, meta = directory / "model.pt", directory / "segmenter.json"
    if not weights.is_file() or not meta.is_file():
        raise FileNotFoundError(f"no segmenter checkpoint in {directory} (model.pt and segmenter.json); "
                                "train one with `racf detector train`")
    architecture = json.loads(meta.read_text())["architecture"]
    try:
        config = SegmenterConfig(**architecture)
    except TypeError:
        raise ValueError(f"the checkpoint in {directory} is of another segmenter architecture (widths "
                         f"{sorted(architecture)}, this one has c1, c2, c3); retrain it with `racf detector train`") from None
    net = SignSegmenterNet(config)
    try:
        net.load_state_dict(torch.load(weights, map_location="cpu", weights_only=True))
    except RuntimeError:  # the same widths, other layers
        raise ValueError(f"the checkpoint in {directory} is of another segmenter architecture (its weights do not "
                         f"fit this network's layers); retrain it with `racf detector train`") from None
    return net.eval()


def image_tensor(rgb: np.ndarray) -> torch.Tensor:
    """(H, W, 3) uint8 -> (1, 3, H, W) float in [0, 1], channels-last (the fast layout on CPU)."""
    x = torch.from_numpy(rgb).permute(2, 0, 1).unsqueeze(0).float().div_(255.0)
    return x.contiguous(memory_format=torch.channels_last)


class LearnedSignDetector(BlobDetector):
    """Finds stop signs with the learned segmenter.

    Args:
        config: post-processing thresholds.
        checkpoint: a checkpoint directory (default: the shipped one).
        net: a network to use instead of loading one (training and tests).
    """

    #: It marks the whole face, white border included: the ground truth it was trained on.
    outline = "face"

    def __init__(self, config: LearnedDetectorConfig | None = None, checkpoint: Path = SHIPPED_SEGMENTER,
                 net: SignSegmenterNet | None = None) -> None:
        self.config = config or LearnedDetectorConfig()
        self.net = (net if net is not None else load_segmenter(checkpoint)).eval()
        self.net = self.net.to(memory_format=torch.channels_last)
        self._logit_threshold = math.log(self.config.threshold / (1.0 - self.config.threshold))

    def scores(self, rgb: np.ndarray) -> np.ndarray:
        """(H, W) float32 logits of the frame, upsampled from the network's half resolution."""
        rgb = check_rgb(rgb)
        h, w = rgb.shape[:2]
        ph, pw = -h % 8, -w % 8
        if ph or pw:  # the network halves three times
            rgb = cv2.copyMakeBorder(rgb, 0, ph, 0, pw, cv2.BORDER_REPLICATE)
        with torch.inference_mode():
            logits = self.net(image_tensor(rgb))[0, 0].numpy()
        full = cv2.resize(logits, (rgb.shape[1], rgb.shape[0]), interpolation=cv2.INTER_LINEAR)
        return full[:h, :w]

    def candidates(self, rgb: np.ndarray) -> list[Detection]:
        """Every component of above-threshold pixels at least ``min_area_px`` large."""
        logits = self.scores(rgb)
        mask = (logits > self._logit_threshold).astype(np.uint8)
        n, labels, stats, centroids = sparse_components(mask)
        out = []
        for i in range(1, n):
            x, y, w, h, area = (int(q) for q in stats[i])
            if area < self.config.min_area_px:
                continue
            comp = labels == i
            confidence = float(np.mean(1.0 / (1.0 + np.exp(-logits[comp]))))
            out.append(Detection(comp, (x, y, x + w, y + h), confidence, area,
                                 (float(centroids[i][0]), float(centroids[i][1]))))
        return out
