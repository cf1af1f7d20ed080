"""The segmenter's dataset on disk: rendered views in shards, named by what made them.

``racf detector data`` renders ``n_train`` training views and ``n_heldout`` held-out views
(a different seed: no pose, lighting or distractor draw is shared) into
``data/detector/<split>/shard-NNN.npz``. A ``manifest.json`` records the settings and the
code version of the simulator and of this package; a dataset whose manifest differs from
what is asked is rendered again, and finished shards of a matching one are kept (an
interrupted run resumes where it stopped).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from racf.experiments.detector.approach_views import draw_approach_view
from racf.experiments.detector.evaluate import VIEW_KINDS
from racf.experiments.detector.views import FAR_RANGE_M, ViewRenderer, ViewSpec, draw_distractors, draw_view
from racf.provenance import code_version

__all__ = ["DatasetSpec", "DEFAULT_DATA_DIR", "make_dataset", "load_split", "SPLITS", "draw_dataset_view"]

DEFAULT_DATA_DIR = Path("data/detector")
SPLITS = ("train", "heldout")
_SHARD = 500
#: What renders a view: the world, the car, its camera and this package's view code.
_RENDER_CODE = ("racf.sim.world", "racf.sim.env", "racf.sim.sensors", "racf.sim.vehicle", "racf.assets.qcar2_map",
                "racf.experiments.detector.views", "racf.experiments.detector.approach_views",
                "racf.experiments.detector.dataset")
#: Sign 1's approach has the most misses in the loop (its plate leaves the image's left edge
#: early on the curve): it gets twice the approach views of each other sign.
APPROACH_SIGN_P = (0.2, 0.4, 0.2, 0.2)


@dataclass(frozen=True)
class DatasetSpec:
    """What a dataset is.

    Attributes:
        seed: the training split's seed; the held-out split's is ``seed + 1_000_003``.
        n_train, n_heldout: views per split.
        sign_share: share of views that look at a stop sign from anywhere around it.
        approach_share: share of views on the car's approaches (along the lane, as the car sees
            the sign; ``racf.experiments.detector.approach_views``). The rest stand anywhere on
            the map, looking anywhere: mostly negatives, with the map's red props.
        far_share: share of the ``sign`` views taken from far off (``FAR_RANGE_M``).
        distractor_p: probability that a view moves props into the picture.
    """

    seed: int = 0
    n_train: int = 10000
    n_heldout: int = 2000
    sign_share: float = 0.45
    approach_share: float = 0.3
    far_share: float = 0.2
    distractor_p: float = 0.5

    def __post_init__(self) -> None:
        for name in ("seed", "n_train", "n_heldout"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < (0 if name == "seed" else 1):
                raise ValueError(f"{name} must be an int >= {0 if name == 'seed' else 1}, got {value!r}")
        for name in ("sign_share", "approach_share", "far_share", "distractor_p"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {getattr(self, name)!r}")
        if self.sign_share + self.approach_share > 1.0:
            raise ValueError(f"sign_share + approach_share must be <= 1, got {self.sign_share + self.approach_share!r}")

    def split_seed(self, split: str) -> int:
        if split not in SPLITS:
            raise ValueError(f"split must be one of {SPLITS}, got {split!r}")
        return self.seed if split == "train" else self.seed + 1_000_003

    def size(self, split: str) -> int:
        return self.n_train if split == "train" else self.n_heldout


def draw_dataset_view(rng: np.random.Generator, spec: DatasetSpec, camera_offset: tuple[float, float]) -> ViewSpec:
    """One view of a dataset of ``spec``: its kind, then the view, from ``rng``."""
    u = rng.random()
    if u < spec.sign_share:
        far = rng.random() < spec.far_share
        return draw_view(rng, "sign", spec.distractor_p, **({"range_m": FAR_RANGE_M} if far else {}))
    if u < spec.sign_share + spec.approach_share:
        view = draw_approach_view(rng, camera_offset, APPROACH_SIGN_P)
        if rng.random() < spec.distractor_p:
            view = replace(view, distractors=draw_distractors(rng, view.camera_xy, view.yaw))
        return view
    return draw_view(rng, "map", spec.distractor_p)


def _manifest(spec: DatasetSpec) -> dict:
    return {"spec": asdict(spec), "code": code_version(*_RENDER_CODE)}


def make_dataset(spec: DatasetSpec = DatasetSpec(), root: Path = DEFAULT_DATA_DIR, progress: bool = True) -> Path:
    """Renders (or resumes) the dataset of ``spec`` under ``root``; returns ``root``."""
    from tqdm import tqdm

    root = Path(root)
    manifest = _manifest(spec)
    path = root / "manifest.json"
    if path.is_file() and json.loads(path.read_text()) != manifest:
        for old in root.glob("*/shard-*.npz"):
            old.unlink()
    root.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")
    renderer = None
    try:
        for split in SPLITS:
            n = spec.size(split)
            # One generator per shard, from the split's seed and the shard's index: shards are
            # independent, so a resumed run renders exactly what an uninterrupted one would.
            shards = range((n + _SHARD - 1) // _SHARD)
            for k in tqdm(shards, desc=f"detector-data {split}", unit="shard", disable=not progress):
                out = root / split / f"shard-{k:03d}.npz"
                if out.is_file():
                    continue
                renderer = renderer or ViewRenderer()
                rng = np.random.default_rng([spec.split_seed(split), k])
                count = min(_SHARD, n - k * _SHARD)
                views = [renderer.render(draw_dataset_view(rng, spec, renderer.camera_offset)) for _ in range(count)]
                out.parent.mkdir(parents=True, exist_ok=True)
                tmp = out.with_suffix(".tmp.npz")
                np.savez_compressed(
                    tmp, rgb=np.stack([v.rgb for v in views]), mask=np.packbits(np.stack([v.mask for v in views]), -1),
                    target=np.packbits(np.stack([v.target for v in views]), -1),
                    sign=np.array([v.spec.sign for v in views], np.int8),
                    kind=np.array([VIEW_KINDS.index(v.spec.kind) for v in views], np.int8),
                    target_share=np.array([v.target_share for v in views], np.float32),
                    faces_share=np.array([v.faces_share for v in views], np.float32), d_true=np.array([v.d_true for v in views]),
                    cam_pos=np.stack([v.cam_pos for v in views]), cam_mat=np.stack([v.cam_mat for v in views]),
                    sign_px=np.array([v.sign_masks for v in views], np.int32))
                tmp.replace(out)  # a shard is there whole or not at all
    finally:
        if renderer is not None:
            renderer.close()
    return root


def load_split(root: Path, split: str) -> dict[str, np.ndarray]:
    """All shards of a split, concatenated: rgb (N, H, W, 3) uint8, mask and target (N, H, W) bool, sign (N,), kind (N,: an index of
    ``VIEW_KINDS``), target_share and faces_share (N,),
    d_true (N,), cam_pos (N, 3), cam_mat (N, 3, 3), sign_px (N, 4)."""
    files = sorted((Path(root) / split).glob("shard-*.npz"))
    if not files:
        raise FileNotFoundError(f"no {split} shards under {root}; render them with `racf detector data`")
    parts = [dict(np.load(f)) for f in files]
    out = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
    width = out["rgb"].shape[2]
    for key in ("mask", "target"):
        out[key] = np.unpackbits(out[key], -1, count=width).astype(bool)
    return out
