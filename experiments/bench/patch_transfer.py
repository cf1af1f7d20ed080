"""``racf bench patch``: the adversarial sticker in the world, against both detectors.

Fresh views (seeded apart from the training and held-out splits) look at a stop sign from
0.3-4 m, up to 60 deg off its face, in varied light; or, with ``views="approach"``, stand on
the car's own approaches (``racf.experiments.detector.approach_views``: where a sticker's size
and place are chosen before the loop measures them). Each is rendered three ways:

- ``clean``: as the map has it;
- ``physical_patch``: with the sticker printed on the viewed sign (the scene's own render:
  perspective, light and resolution as the world gives them);
- ``patch_occlusion``: the image-space occluder of the same area share pasted over the top
  rows of the sign's pixels (``racf.sim.attacks.patch_occlusion``).

For each detector and rendering: recall over the views whose sign is resolvable (see
``racf.experiments.detector.evaluate``), with Wilson intervals, overall and by distance. The
sticker optimised against the learned segmenter tried on the classical detector, and the
occluder tried on the learned one, are the transfer report.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from racf.controllers.detectors import DETECTORS, make_detector
from racf.experiments.detector.evaluate import DISTANCE_BANDS_M, DetectionCounts, band_label, score_frame
from racf.experiments.detector.views import ViewRenderer, draw_view

#: Where the views stand: anywhere around the sign, or on the car's approaches.
VIEW_SOURCES = ("sign", "approach")

__all__ = ["PatchBenchResult", "bench_patch", "RENDERINGS", "DISTANCE_BANDS_M", "occluded"]

RENDERINGS = ("clean", "physical_patch", "patch_occlusion")
#: The views' seed: apart from the training (0) and held-out (1000003) splits.
SEED = 2_000_029


@dataclass
class PatchBenchResult:
    """Counts per (detector, rendering), overall and per distance band."""

    texture: str
    size: float
    position: tuple[float, float]
    n_views: int
    counts: dict[str, dict[str, DetectionCounts]] = field(default_factory=dict)
    by_band: dict[str, dict[str, dict[str, DetectionCounts]]] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"texture": self.texture, "size": self.size, "position": list(self.position), "n_views": self.n_views,
                "counts": {d: {r: c.to_dict() for r, c in row.items()} for d, row in self.counts.items()},
                "by_band": {d: {r: {b: c.to_dict() for b, c in bands.items()} for r, bands in row.items()}
                            for d, row in self.by_band.items()}}


def _band(d: float) -> str | None:
    for lo, hi in DISTANCE_BANDS_M:
        if lo <= d < hi or (hi == DISTANCE_BANDS_M[-1][1] and d == hi):
            return band_label(lo, hi)
    return None


def occluded(rgb: np.ndarray, target: np.ndarray, share: float, rng: np.random.Generator) -> np.ndarray:
    """``rgb`` with the occluder (a naturalistic texture) pasted over a ``share`` of the sign's
    pixels (the top rows), as ``patch_occlusion`` does."""
    from racf.sim.attacks.patch_occlusion import paste_occluder
    from racf.sim.world.patch_texture import natural_texture

    return paste_occluder(rgb, target, share, natural_texture(rng))


def bench_patch(n_views: int = 400, texture: str = "learned", size: float = 0.5,
                position: tuple[float, float] | str = (0.0, 0.0), detectors: tuple[str, ...] = tuple(DETECTORS),
                seed: int = SEED, progress: bool = True, keep_examples: int = 0,
                views: str = "sign") -> tuple[PatchBenchResult, list]:
    """Runs the transfer benchmark. Returns the result and up to ``keep_examples`` example
    (clean, patched) frame pairs of near views (for the README's picture)."""
    from tqdm import tqdm

    from racf.experiments.detector.approach_views import draw_approach_view

    if views not in VIEW_SOURCES:
        raise ValueError(f"views must be one of {VIEW_SOURCES}, got {views!r}")
    from racf.sim.world.sign_patch import PatchPlacement, load_patch_texture

    placement = PatchPlacement(area_share=size, centre=position)
    rng = np.random.default_rng(seed)
    tex = load_patch_texture(texture, rng=np.random.default_rng([seed, 1]))
    dets = {name: make_detector(name) for name in detectors}
    result = PatchBenchResult(texture, size, placement.centre, n_views)
    result.counts = {d: {r: DetectionCounts() for r in RENDERINGS} for d in detectors}
    result.by_band = {d: {r: {_band(lo): DetectionCounts() for lo, _ in DISTANCE_BANDS_M} for r in RENDERINGS}
                      for d in detectors}
    examples = []
    renderer = ViewRenderer()
    env = renderer.env.unwrapped
    try:
        for _ in tqdm(range(n_views), desc="bench-patch", unit="view", disable=not progress):
            spec = draw_view(rng, "sign") if views == "sign" else draw_approach_view(rng, renderer.camera_offset)
            env.hide_sign_patches()
            clean = renderer.render(spec)
            env.show_sign_patch(spec.sign, tex, placement)
            patched = renderer.render(spec)
            env.hide_sign_patches()
            frames = {"clean": clean.rgb, "physical_patch": patched.rgb,
                      "patch_occlusion": occluded(clean.rgb, clean.target, size, rng)}
            band = _band(clean.d_true)
            for name, det in dets.items():
                for rendering, rgb in frames.items():
                    hit, fp = score_frame(det.detect(rgb), clean.target, clean.mask, clean.target_share)
                    result.counts[name][rendering].add(hit, fp)
                    if band is not None:
                        result.by_band[name][rendering][band].add(hit, fp)
            if len(examples) < keep_examples and 0.4 <= clean.d_true <= 0.9 and clean.target.sum() > 400:
                examples.append((clean.rgb, patched.rgb, clean.target))
    finally:
        renderer.close()
    return result, examples
