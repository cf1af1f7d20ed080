"""The stickers each stop sign carries (``racf.sim.world.sign_patch``): a box geom just in front of
the plate, with a texture of its own, in the group no sensor sees until one is shown."""

from __future__ import annotations

import cv2
import numpy as np

from racf.sim.world.scene import HIDDEN_GEOM_GROUP, PROP_GEOM_GROUP, patch_geom, patch_texture
from racf.sim.world.sign_patch import PatchPlacement
from racf.sim.world.stop_signs import SignGeometry

__all__ = ["Stickers"]


class Stickers:
    """Stop sign ``i``'s sticker geom and texture, for ``n_signs`` signs."""

    def __init__(self, model, n_signs: int) -> None:
        self.geoms = [model.geom(patch_geom(i)).id for i in range(n_signs)]
        self.textures = [model.texture(patch_texture(i)).id for i in range(n_signs)]

    def show(self, model, sign_geometry: SignGeometry, sign_index: int, texture: np.ndarray,
             placement: PatchPlacement) -> int:
        """Writes ``texture`` into sign ``sign_index``'s sticker, sizes and places its geom as ``placement``
        says and makes it seen; returns the texture's id (to upload to the renderers)."""
        if sign_index not in range(len(self.geoms)):
            raise ValueError(f"sign_index must be 0..{len(self.geoms) - 1}, got {sign_index!r}")
        if not isinstance(placement, PatchPlacement):
            raise TypeError(f"placement must be a PatchPlacement, got {type(placement).__name__}")
        texture = np.asarray(texture)
        if texture.ndim != 3 or texture.shape[2] != 3 or texture.dtype != np.uint8:
            raise ValueError(f"texture must be an (H, W, 3) uint8 image, got shape {texture.shape} dtype {texture.dtype}")
        geom, tex = self.geoms[sign_index], self.textures[sign_index]
        size = (int(model.tex_width[tex]), int(model.tex_height[tex]))
        if texture.shape[:2] != size[::-1]:
            texture = cv2.resize(texture, size, interpolation=cv2.INTER_AREA)
        adr, n = int(model.tex_adr[tex]), int(model.tex_nchannel[tex])
        model.tex_data[adr:adr + texture.size // 3 * n] = texture.reshape(-1) if n == 3 else \
            np.concatenate([texture, np.full(texture.shape[:2] + (1,), 255, np.uint8)], 2).reshape(-1)
        corners = placement.corners_local(sign_geometry)
        model.geom_pos[geom] = [corners[0, 0] - model.geom_size[geom][0], *corners[:, 1:].mean(axis=0)]
        model.geom_size[geom][1:] = placement.side_m / 2
        model.geom_group[geom] = PROP_GEOM_GROUP
        return tex

    def hide(self, model) -> None:
        """Takes every sticker off (back to the group no sensor sees)."""
        for geom in self.geoms:
            model.geom_group[geom] = HIDDEN_GEOM_GROUP
