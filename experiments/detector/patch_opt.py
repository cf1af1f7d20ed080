"""``racf detector optimise-patch``: an adversarial sticker for the stop sign, against the learned segmenter.

Expectation over transformation (Athalye et al. 2018; Brown et al. 2017, "Adversarial
Patch"; Eykholt et al. 2018, "Robust Physical-World Attacks"): MuJoCo's renderer is not
differentiable, so the patch is put into *rendered* frames of the training split by a
differentiable perspective warp (kornia), using the sign's known pose in each frame: the
sticker's four corners on the plate (``racf.sim.world.sign_patch.PatchPlacement``) are projected
with the camera's pose and intrinsics, and the texture is warped onto them. Over a batch of
views (distances 0.3-4 m, up to 60 deg off the face, the room's lighting as rendered) and
random transformations (pose error of a pixel, the light's gain and tint, sensor noise,
blur), the texture is moved to minimise the segmenter's scores on the sign's pixels: the
mask the car needs is suppressed. The texture's colours are kept printable (in [0, 1]) by
a sigmoid, and a small total-variation term keeps it free of single-pixel noise a camera
would blur away.

With ``views="approach"`` (``--views approach``) the views are instead the car's own approaches,
weighted to the frames where detection decides the stop
(:mod:`racf.experiments.detector.approach_views`): an expectation over the loop, not over
any frame. That sticker ships as ``learned-approach``.

The result is a 64x64 PNG (``assets/patches/learned.png``) that the scene prints on the sign
(``physical_patch``); every view then renders it as the world would. Seeded: the same seed
and thread count give the same texture.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional as F

from racf.controllers.learned_detector import SHIPPED_SEGMENTER, load_segmenter
from racf.controllers.segmenter_net import SignSegmenterNet
from racf.experiments.detector.dataset import load_split
from racf.sim.world.sign_patch import PatchPlacement
from racf.sim.world.stop_signs import stop_signs
from racf.assets import asset_path

__all__ = ["PatchConfig", "optimise_patch", "patch_corners_px", "composite", "SHIPPED_PATCH_DIR"]

SHIPPED_PATCH_DIR = asset_path("patches")
_MJ_TO_OPTICAL = np.diag([1.0, -1.0, -1.0])
#: The red face's colour in the scene (``racf.sim.world.scene``): a rendered face pixel over it is
#: the light's gain at that view.
_FACE_RED = 0.80
TEXTURE_PX = 64
#: Where the expectation's views come from (``PatchConfig.views``).
VIEW_SOURCES = ("dataset", "approach")


@dataclass(frozen=True)
class PatchConfig:
    """Optimisation settings.

    Attributes:
        seed: initial texture, batch order and every transformation draw.
        size: the sticker's area as a share of the plate (``PatchPlacement.area_share``).
        position: its centre on the plate, (right, up) in across-flats units, or a name of
            ``racf.sim.world.sign_patch.POSITIONS`` (as far that way as it stays on the plate).
        steps: optimiser steps.
        batch: views per step.
        lr: Adam's learning rate on the texture's logits.
        tv_weight: weight of the total-variation term.
        min_sign_px: views whose sign covers fewer pixels are left out.
        threads: torch CPU threads.
        views: ``dataset``, the detector's training views (any distance and angle); or
            ``approach``, views rendered on the car's approaches and weighted to the frames where
            detection decides the stop (:mod:`racf.experiments.detector.approach_views`): the
            expectation over the loop, not the frame.
        n_approach: approach views rendered (``views="approach"``; about 40 % show the sign
            large enough).
    """

    seed: int = 0
    size: float = 0.5
    position: tuple[float, float] = (0.0, 0.0)
    steps: int = 600
    batch: int = 16
    lr: float = 0.1
    tv_weight: float = 0.02
    min_sign_px: int = 30
    threads: int = 2
    views: str = "dataset"
    n_approach: int = 3000

    def __post_init__(self) -> None:
        for name, lo, hi in (("seed", 0, 2**31), ("steps", 1, 100_000), ("batch", 1, 512), ("min_sign_px", 1, 10**6),
                             ("threads", 1, 256)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
                raise ValueError(f"{name} must be an int in [{lo}, {hi}], got {value!r}")
        if not 0 < self.lr <= 10:
            raise ValueError(f"lr must be in (0, 10], got {self.lr!r}")
        if self.views not in VIEW_SOURCES:
            raise ValueError(f"views must be one of {VIEW_SOURCES}, got {self.views!r}")
        if isinstance(self.n_approach, bool) or not isinstance(self.n_approach, int) or not 1 <= self.n_approach <= 10**6:
            raise ValueError(f"n_approach must be an int in [1, 1000000], got {self.n_approach!r}")
        if not 0 <= self.tv_weight <= 10:
            raise ValueError(f"tv_weight must be in [0, 10], got {self.tv_weight!r}")
        if isinstance(self.position, str):  # a named place: resolved to where the sticker then sits
            object.__setattr__(self, "position", PatchPlacement(area_share=self.size, centre=self.position).centre)
        object.__setattr__(self, "position", tuple(float(v) for v in self.position))
        self.placement  # validates size and position (the sticker must lie on the plate)

    @property
    def placement(self) -> PatchPlacement:
        return PatchPlacement(area_share=self.size, centre=self.position)


def patch_corners_px(placement: PatchPlacement, sign_index: int, cam_pos: np.ndarray, cam_mat: np.ndarray,
                     intrinsics) -> np.ndarray | None:
    """(4, 2) pixel positions of the sticker's corners (top-left, top-right, bottom-right,
    bottom-left) in a frame, or None when a corner is behind the camera."""
    corners = placement.corners_world(stop_signs()[sign_index])
    opt = (_MJ_TO_OPTICAL @ np.asarray(cam_mat).T @ (corners - np.asarray(cam_pos)).T).T
    if (opt[:, 2] <= 0.05).any():
        return None
    return intrinsics.project(opt)


def composite(images: torch.Tensor, texture: torch.Tensor, corners: torch.Tensor, visible: torch.Tensor,
              gain: torch.Tensor) -> torch.Tensor:
    """Frames with the texture warped onto the sticker's corners.

    Args:
        images: (N, 3, H, W) frames in [0, 1].
        texture: (3, T, T) in [0, 1] (row 0 the sticker's top edge, as seen from in front).
        corners: (N, 4, 2) corner pixels (top-left, top-right, bottom-right, bottom-left).
        visible: (N, 1, H, W) where the plate is visible (the sticker is on it: where the plate
            is hidden, so is the sticker).
        gain: (N, 3, 1, 1) light on the plate: rendered colour = texture colour x gain.
    """
    from kornia.geometry.transform import get_perspective_transform, warp_perspective

    n, _, h, w = images.shape
    t = texture.shape[-1]
    # Texel centres sit half a texel in from the sticker's edges: the texture's outer edges
    # (-0.5 and t - 0.5 in texel coordinates) go onto the corners.
    lo, hi = -0.5, t - 0.5
    src = torch.tensor([[lo, lo], [hi, lo], [hi, hi], [lo, hi]]).expand(n, 4, 2)
    # In double precision: a sticker seen nearly edge-on makes the 8x8 solve ill-conditioned.
    m = get_perspective_transform(src.double(), corners.double()).float()
    stack = torch.cat([texture.expand(n, -1, -1, -1), torch.ones(n, 1, t, t)], 1)
    warped = warp_perspective(stack, m, dsize=(h, w), mode="bilinear", padding_mode="zeros", align_corners=True)
    alpha = warped[:, 3:] * visible
    return images * (1 - alpha) + (warped[:, :3] * gain).clamp(0, 1) * alpha


def _view_gain(rgb: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(3,) the light on the plate in a frame: its red face's rendered colour over the material's."""
    px = rgb[target].astype(np.float32) / 255.0
    red = px[(px[:, 0] > 0.25) & (px[:, 0] > 2.5 * px[:, 1])]
    if len(red) < 4:
        return np.ones(3, np.float32)
    g = float(np.median(red[:, 0])) / _FACE_RED
    return np.full(3, g, np.float32)


def _tv(x: torch.Tensor) -> torch.Tensor:
    return (x[:, 1:, :] - x[:, :-1, :]).abs().mean() + (x[:, :, 1:] - x[:, :, :-1]).abs().mean()


def _eot_views(data: dict[str, np.ndarray], config: PatchConfig, intrinsics) -> dict[str, np.ndarray]:
    """The training views an attack can use: a stop sign in view, large enough, corners in front."""
    keep, corners = [], []
    for i in range(len(data["rgb"])):
        s = int(data["sign"][i])
        if s < 0 or data["target"][i].sum() < config.min_sign_px:
            continue
        c = patch_corners_px(config.placement, s, data["cam_pos"][i], data["cam_mat"][i], intrinsics)
        if c is not None:
            keep.append(i)
            corners.append(c)
    keep = np.array(keep, int)
    weight = data["weight"][keep] if "weight" in data else np.ones(len(keep))
    return {"index": keep, "corners": np.array(corners, np.float32),
            "gain": np.stack([_view_gain(data["rgb"][i], data["target"][i]) for i in keep]),
            "weight": np.asarray(weight, np.float32)}


def optimise_patch(config: PatchConfig = PatchConfig(), data_root: Path = Path("data/detector"),
                   checkpoint: Path = SHIPPED_SEGMENTER, out_dir: Path | None = None, progress: bool = True,
                   net: SignSegmenterNet | None = None) -> tuple[np.ndarray, dict]:
    """Optimises a sticker texture; returns it ((64, 64, 3) uint8) and a report (settings, losses,
    the segmenter's recall on the training views with and without it, composited)."""
    from tqdm import tqdm

    from racf.sim.sensors.camera import CameraIntrinsics

    torch.set_num_threads(config.threads)
    g = torch.Generator().manual_seed(config.seed)
    net = (net or load_segmenter(checkpoint)).eval()
    for p in net.parameters():
        p.requires_grad_(False)
    if config.views == "approach":
        from racf.experiments.detector.approach_views import approach_views

        data = approach_views(config.n_approach, config.seed, progress=progress)
    else:
        data = load_split(data_root, "train")
    h, w = data["rgb"].shape[1:3]
    intrinsics = CameraIntrinsics.d435_colour(w, h)
    views = _eot_views(data, config, intrinsics)
    if len(views["index"]) < config.batch:
        raise ValueError(f"only {len(views['index'])} training views show a sign of >= {config.min_sign_px} px; "
                         f"need at least batch = {config.batch}")
    images = torch.from_numpy(data["rgb"][views["index"]]).permute(0, 3, 1, 2)
    targets = torch.from_numpy(data["target"][views["index"]]).unsqueeze(1).float()
    half_targets = F.max_pool2d(targets, 2)
    corners = torch.from_numpy(views["corners"])
    gains = torch.from_numpy(views["gain"]).view(-1, 3, 1, 1)
    weights = torch.from_numpy(views["weight"])
    logits_tex = (torch.randn(3, TEXTURE_PX, TEXTURE_PX, generator=g) * 0.5).requires_grad_(True)
    opt = torch.optim.Adam([logits_tex], lr=config.lr)
    n = len(images)
    losses = []
    t0 = time.perf_counter()
    bar = tqdm(range(config.steps), desc="optimise-patch", unit="step", disable=not progress)
    for _ in bar:
        idx = torch.randint(n, (config.batch,), generator=g)
        x = images[idx].float().div_(255.0)
        # The transformations the sticker must survive: a pixel of pose error per corner,
        # the light's gain (+-25 %) and tint, sensor noise and, on half the views, a blur.
        jitter = (torch.rand(config.batch, 4, 2, generator=g) - 0.5) * 2.0
        gain = gains[idx] * (0.75 + 0.5 * torch.rand(config.batch, 1, 1, 1, generator=g)) \
            * (0.94 + 0.12 * torch.rand(config.batch, 3, 1, 1, generator=g))
        texture = torch.sigmoid(logits_tex)
        x = composite(x, texture, corners[idx] + jitter, targets[idx], gain)
        x = x + torch.randn(x.shape, generator=g) * 0.02
        blur = torch.rand(config.batch, 1, 1, 1, generator=g) < 0.5
        x = torch.where(blur, F.avg_pool2d(F.pad(x, (1, 1, 1, 1), mode="replicate"), 3, stride=1), x)
        logits = net(x.clamp(0, 1).contiguous(memory_format=torch.channels_last))
        m = half_targets[idx]
        # Push every sign cell below the threshold, the highest hardest (a component needs only
        # a few cells to survive).
        per_cell = F.softplus(logits + 2.0) * m
        soft = per_cell.sum(dim=(1, 2, 3)) / m.sum(dim=(1, 2, 3)).clamp(min=1)
        peak = torch.logsumexp(torch.where(m > 0, logits, torch.full_like(logits, -30.0)).flatten(1), 1)
        w = weights[idx] / weights[idx].sum()
        loss = (w * (soft + 0.5 * F.relu(peak + 2.0))).sum() + config.tv_weight * _tv(texture)
        opt.zero_grad(set_to_none=True)
        if not torch.isfinite(loss):  # a degenerate view in the batch: draw another batch
            continue
        loss.backward()
        torch.nan_to_num_(logits_tex.grad, nan=0.0, posinf=0.0, neginf=0.0)
        opt.step()
        losses.append(float(loss.detach()))
        bar.set_postfix(loss=f"{np.mean(losses[-20:]):.3f}")
    texture = (torch.sigmoid(logits_tex.detach()).permute(1, 2, 0).numpy() * 255).round().astype(np.uint8)
    report = {"config": {**asdict(config), "position": list(config.position)}, "n_views": n,
              "optimise_s": time.perf_counter() - t0, "loss_first": float(np.mean(losses[:20])),
              "loss_last": float(np.mean(losses[-20:])),
              # Which segmenter it was optimised against: a sticker is only adversarial to its own.
              "segmenter_sha256": _weights_digest(net)}
    if out_dir is not None:
        save_patch(texture, Path(out_dir), report)
    return texture, report


def _weights_digest(net: SignSegmenterNet) -> str:
    """SHA-256 of the network's weights (the same for a checkpoint wherever it is loaded)."""
    import hashlib

    h = hashlib.sha256()
    for name, tensor in sorted(net.state_dict().items()):
        h.update(name.encode())
        h.update(tensor.detach().contiguous().numpy().tobytes())
    return h.hexdigest()


def save_patch(texture: np.ndarray, out_dir: Path, report: dict, name: str = "learned") -> Path:
    """Writes ``<name>.png`` and ``<name>.json`` (what made it) into ``out_dir``."""
    import cv2

    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{name}.png"
    cv2.imwrite(str(path), cv2.cvtColor(texture, cv2.COLOR_RGB2BGR))
    (out_dir / f"{name}.json").write_text(json.dumps(report, indent=2, sort_keys=True) + "\n")
    return path
