"""A sticker printed on a stop sign's plate: where it sits, how large it is, and its picture.

The scene gives every stop sign a hidden square sticker just in front of its face
(``racf.sim.world.scene``); the env shows it with a texture and a :class:`PatchPlacement`
(``QCar2Env.show_sign_patch``), and every camera view then renders it as the world would.

Coordinates on the plate are seen from in front of the sign: ``right`` and ``up`` from the
plate's centre, in units of the plate's width across flats (``SIGN_FACE_ACROSS_FLATS_M``).
In the sign's body frame the face looks along +x, +y is the viewer's right and +z is up.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from racf.sim.world.stop_signs import SIGN_FACE_ACROSS_FLATS_M, SignGeometry, StopSign
from racf.assets import asset_path

__all__ = ["PatchPlacement", "POSITIONS", "PATCHES_DIR", "TEXTURE_PX", "PATCH_FRONT_X_M", "load_patch_texture",
           "shipped_patches", "OCTAGON_AREA"]

#: The shipped sticker textures (``<name>.png``).
PATCHES_DIR = asset_path("patches")
#: The scene's sticker textures are this many texels a side.
TEXTURE_PX = 64
#: The sticker's front surface, m in front of the sign body's origin (the red face is at 0.001 m).
PATCH_FRONT_X_M = 0.0013
#: A regular octagon's area over its across-flats width squared.
OCTAGON_AREA = 2.0 * (math.sqrt(2.0) - 1.0)
#: Named positions: the direction the sticker is pushed from the centre, as far as it stays on the plate.
POSITIONS = {"centre": (0.0, 0.0), "top": (0.0, 1.0), "bottom": (0.0, -1.0), "left": (-1.0, 0.0),
             "right": (1.0, 0.0)}


def _on_plate(half_side: float, right: float, up: float) -> bool:
    """Whether a square of half side ``half_side`` centred at (right, up) lies on the octagon
    (flats at 0.5 from the centre, all in across-flats units)."""
    h = 0.5 + 1e-9
    for sx in (-1, 1):
        for sy in (-1, 1):
            x, y = right + sx * half_side, up + sy * half_side
            if abs(x) > h or abs(y) > h or abs(x) + abs(y) > h * math.sqrt(2.0):
                return False
    return True


@dataclass(frozen=True)
class PatchPlacement:
    """A square sticker on the plate.

    Attributes:
        area_share: the sticker's area over the plate's (the octagon), in (0, 0.6].
        centre: (right, up) of its centre from the plate's centre, across-flats units, each in
            [-0.5, 0.5]; or a name of ``POSITIONS`` (``centre``, ``top``, ``bottom``, ``left``,
            ``right``): pushed that way as far as the sticker stays on the plate.

    Raises:
        ValueError: a value that is not a number, out of range, or a sticker that leaves the plate.
    """

    area_share: float = 0.5
    centre: tuple[float, float] | str = (0.0, 0.0)

    def __post_init__(self) -> None:
        a = self.area_share
        if isinstance(a, bool) or not isinstance(a, numbers.Real) or not 0.0 < a <= 0.6:
            raise ValueError(f"PatchPlacement.area_share must be a number in (0, 0.6] (the sticker's area over the "
                             f"plate's), got {a!r}")
        object.__setattr__(self, "area_share", float(a))
        centre = self.centre
        if isinstance(centre, str):
            if centre not in POSITIONS:
                raise ValueError(f"PatchPlacement.centre must be (right, up) or one of {tuple(POSITIONS)}, "
                                 f"got {centre!r}")
            centre = self._farthest(POSITIONS[centre])
        try:
            right, up = (float(v) for v in centre)
            if any(isinstance(v, bool) for v in centre):
                raise TypeError
        except (TypeError, ValueError):
            raise ValueError(f"PatchPlacement.centre must be (right, up) numbers in [-0.5, 0.5] or one of "
                             f"{tuple(POSITIONS)}, got {self.centre!r}") from None
        if not (-0.5 <= right <= 0.5 and -0.5 <= up <= 0.5) or math.isnan(right) or math.isnan(up):
            raise ValueError(f"PatchPlacement.centre must lie in [-0.5, 0.5] x [-0.5, 0.5], got {self.centre!r}")
        if not _on_plate(self.side / 2, right, up):
            raise ValueError(f"a sticker of area_share {self.area_share} ({self.side:.3f} across-flats a side) centred "
                             f"at {(right, up)} leaves the plate; move it towards the centre or make it smaller")
        object.__setattr__(self, "centre", (right, up))

    @property
    def side(self) -> float:
        """The square's side, across-flats units."""
        return math.sqrt(self.area_share * OCTAGON_AREA)

    @property
    def side_m(self) -> float:
        """The square's side, m."""
        return self.side * SIGN_FACE_ACROSS_FLATS_M

    def _farthest(self, direction: tuple[float, float]) -> tuple[float, float]:
        """The centre farthest along ``direction`` that keeps the sticker on the plate (bisection)."""
        half = math.sqrt(float(self.area_share) * OCTAGON_AREA) / 2
        if not _on_plate(half, 0.0, 0.0):
            return (0.0, 0.0)  # too large anywhere: the range check reports it
        lo, hi = 0.0, 0.5
        for _ in range(40):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if _on_plate(half, direction[0] * mid, direction[1] * mid) else (lo, mid)
        lo = math.floor(lo * 1e6) / 1e6  # rounded towards the centre: still on the plate
        return (direction[0] * lo + 0.0, direction[1] * lo + 0.0)

    def corners_local(self, geometry: SignGeometry) -> np.ndarray:
        """(4, 3) corners in the sign's body frame: top-left, top-right, bottom-right, bottom-left
        as seen from in front; x is the sticker's front surface."""
        right, up = self.centre
        w = SIGN_FACE_ACROSS_FLATS_M
        y0, z0, h = right * w, geometry.centre_height_m + up * w, self.side_m / 2
        return np.array([[PATCH_FRONT_X_M, y0 - h, z0 + h], [PATCH_FRONT_X_M, y0 + h, z0 + h],
                         [PATCH_FRONT_X_M, y0 + h, z0 - h], [PATCH_FRONT_X_M, y0 - h, z0 - h]])

    def corners_world(self, sign: StopSign) -> np.ndarray:
        """(4, 3) the same corners in the map frame."""
        local = self.corners_local(sign.geometry)
        c, s = math.cos(sign.face_yaw), math.sin(sign.face_yaw)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return local @ rot.T + np.array([*sign.position, 0.0])


def shipped_patches() -> tuple[str, ...]:
    """Names of the shipped sticker textures."""
    return tuple(sorted(p.stem for p in PATCHES_DIR.glob("*.png")))


def load_patch_texture(texture: str, rng: np.random.Generator | None = None) -> np.ndarray:
    """A sticker's picture, (64, 64, 3) uint8, row 0 its top edge and column 0 its left edge as
    seen from in front.

    Args:
        texture: a shipped name (``assets/patches/<name>.png``), ``natural`` (a naturalistic
            sticker drawn from ``rng``: what the occluder shows), or a path to a PNG.
        rng: the generator of a ``natural`` sticker.
    """
    import cv2

    if not isinstance(texture, str) or not texture:
        raise ValueError(f"texture must be a shipped name {shipped_patches()}, 'natural' or a PNG path, "
                         f"got {texture!r}")
    if texture == "natural":
        from racf.sim.world.patch_texture import natural_texture

        return natural_texture(rng if rng is not None else np.random.default_rng(0), TEXTURE_PX)
    path = PATCHES_DIR / f"{texture}.png" if "/" not in texture and not texture.endswith(".png") else Path(texture)
    image = cv2.imread(str(path), cv2.IMREAD_COLOR) if path.is_file() else None
    if image is None:
        raise ValueError(f"no sticker texture {texture!r} (looked for {path}); shipped: {shipped_patches()}, "
                         "'natural', or a PNG path (make one with `racf detector optimise-patch`)")
    image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
    if image.shape[:2] != (TEXTURE_PX, TEXTURE_PX):
        image = cv2.resize(image, (TEXTURE_PX, TEXTURE_PX), interpolation=cv2.INTER_AREA)
    return image
