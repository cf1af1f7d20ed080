"""Whether the car ahead the camera sees is a car or a picture of one.

A car is a solid: where its box stands in the picture, the depth finds something upright at the
distance the box's size implies. A picture of a car (projected, on a screen, drawn into the
camera's image: the phantom of Nassi et al., CCS 2020) gives the camera a box and the range
sensors nothing there: the depth and the LiDAR see the road and what stands behind it.

A box the depth does not hold up is not proof of a picture on its own: the depth may be the one
attacked (a patch that reads the car far, Cheng et al., ECCV 2022), and then the box is the honest
witness. What moved tells the two apart. The check takes the box for a picture when:
- the depth sees nothing upright on the lane in the box at all, only the floor; or
- the box was held up a moment ago, and since then it has moved further than what stands on the
  lane in it: the box left the car, not the car the box (a car does not appear out of nowhere in
  front of another; a picture does).
Where the box stayed (as far as a car can move) and what stood in it did not (a depth read far,
the frustum attack moving the depth and the LiDAR together), the range sensors are the ones
attacked, and the check catches no picture for the rest of the episode. The LiDAR is no second
witness here: its tracker picks its cluster near the depth it is given, so at a first sight it
sides with whatever the depth reads, attacked or not. A picture that stands over a car from the
first frame the car sees it is therefore not caught: the check errs towards braking for nothing,
never towards driving into a car.

Once caught, the picture is remembered while no box is held up (a box at the image's edge, whose
size cannot be measured, is still the picture); a held-up box ends it, and a next picture must be
caught again. The check forgets everything when the car ahead is lost from sight.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from racf.controllers.detector import Detection
from racf.controllers.distance import CameraModel

__all__ = ["LeadExistenceConfig", "LeadEvidence", "LeadExistenceCheck", "NO_EVIDENCE", "box_points", "in_lane"]


@dataclass(frozen=True)
class LeadExistenceConfig:
    """The check's settings.

    Attributes:
        lane_half_width_m: what stands within this of the lane's centre is on the lane, m (the car
            ahead is; the walls and what stands beside the lane are not).
        support_tol: a depth within this share of the box's size distance (plus ``support_abs_m``)
            stands where the box says.
        support_abs_m: the absolute part of that tolerance, m (the depth's noise at short range).
        min_support: the share of the box's pixels on the lane that must show something upright
            there for the box to be held up (a real car's rear fills most of its box).
        min_pixels: the fewest pixels on the lane a box needs for a verdict (fewer: no verdict).
        closing_mps: the fastest the car ahead closes or draws away, m/s (the QCar 2's top speed).
        jump_margin_m: what the nearest upright thing, or the box's size distance, may move on top of
            that between two frames, m (their own noise).
        memory_s: how long a held-up box is remembered for the jump test, s.
        nearest_quantile: the nearest upright thing is this quantile of the upright depths (a low
            one, robust to a stray pixel).
    """

    lane_half_width_m: float = 0.15
    support_tol: float = 0.15
    support_abs_m: float = 0.05
    min_support: float = 0.15
    min_pixels: int = 20
    closing_mps: float = 3.0
    jump_margin_m: float = 0.15
    memory_s: float = 1.0
    nearest_quantile: float = 0.1

    def __post_init__(self) -> None:
        for name, lo, hi in (("lane_half_width_m", 0.0, 1.0), ("support_tol", 0.0, 1.0), ("support_abs_m", 0.0, 1.0),
                             ("min_support", 0.0, 1.0), ("closing_mps", 0.0, 20.0), ("jump_margin_m", 0.0, 5.0), ("memory_s", 0.0, 10.0),
                             ("nearest_quantile", 0.0, 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
                raise ValueError(f"{name} must be in [{lo}, {hi}], got {value!r}")
        if isinstance(self.min_pixels, bool) or not isinstance(self.min_pixels, int) or self.min_pixels < 1:
            raise ValueError(f"min_pixels must be an int >= 1, got {self.min_pixels!r}")

    def tolerance(self, distance_m: float) -> float:
        """How far a depth may lie from ``distance_m`` and stand there, m."""
        return self.support_abs_m + self.support_tol * distance_m


@dataclass(frozen=True)
class LeadEvidence:
    """What the check made of one frame's box.

    Attributes:
        support: the share of the box's pixels on the lane that show something upright at its size
            distance (NaN: no verdict: no box, no size, or too few pixels on the lane).
        nearest_m: the nearest upright thing on the lane in the box, m (NaN: none seen).
        picture: the box is taken for a picture: its size is no witness, and the distance is
            ``nearest_m``'s.
        caught: a picture was caught, and no box has been held up since.
    """

    support: float
    nearest_m: float
    picture: bool
    caught: bool

    def columns(self) -> dict[str, float]:
        """The step log's columns."""
        return {"lead_support": self.support, "lead_nearest": self.nearest_m, "lead_picture": float(self.picture)}


NO_EVIDENCE = LeadEvidence(math.nan, math.nan, False, False)


def box_points(depth: np.ndarray, box: tuple[int, int, int, int], camera: CameraModel,
               camera_height_m: float, step_rows: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """What the depth shows in ``box`` (x0, y0, x1, y1): (N, 2) points as (z ahead along the optical
    axis, y left), m, and (N,) bool, whether each shows something upright.

    A pixel is upright where the depth barely changes down its column: the floor's depth falls by
    z^2 / (fy h) per row (h the camera's height), an upright face's by nothing. The test reads that
    slope, not the pixel's height, so a car pitching under braking does not turn the floor upright."""
    h, w = depth.shape
    x0, y0, x1, y1 = max(int(box[0]), 0), max(int(box[1]), 0), min(int(box[2]), w), min(int(box[3]), h - step_rows)
    if x1 <= x0 or y1 <= y0:
        return np.empty((0, 2)), np.empty(0, bool)
    z = depth[y0:y1, x0:x1].astype(float)
    below = depth[y0 + step_rows:y1 + step_rows, x0:x1].astype(float)
    fy = camera.fy if camera.fy is not None else camera.fx
    rows, cols = np.nonzero(np.isfinite(z) & (z > 0))
    ahead, under = z[rows, cols], below[rows, cols]
    floor_fall = step_rows * ahead * ahead / (fy * camera_height_m)
    upright = np.isfinite(under) & (under > 0) & (np.abs(ahead - under) < 0.5 * floor_fall)
    left = (camera.cx - (cols + x0 + 0.5)) * ahead / camera.fx
    return np.column_stack([ahead, left]), upright


def in_lane(points: np.ndarray, lane: np.ndarray, half_width_m: float) -> np.ndarray:
    """(N,) bool: the ``points`` (z, y) within ``half_width_m`` of a point of ``lane`` ((M, 2) z, y)."""
    if not len(points) or not len(lane):
        return np.zeros(len(points), bool)
    gaps, _ = cKDTree(lane).query(points, distance_upper_bound=half_width_m * 1.0001)
    return gaps <= half_width_m


class LeadExistenceCheck:
    """Per new frame: whether the detection's box stands where its size says (:class:`LeadEvidence`).

    Args:
        camera: the camera's intrinsics.
        camera_height_m: its height above the floor, m.
        config: the settings.
    """

    def __init__(self, camera: CameraModel, camera_height_m: float, config: LeadExistenceConfig | None = None) -> None:
        self.camera = camera
        self.camera_height_m = float(camera_height_m)
        self.config = config or LeadExistenceConfig()
        self.reset()

    def reset(self) -> None:
        """A new episode: forget the last box and any picture caught."""
        self.last = NO_EVIDENCE
        self._caught = False
        self._moved = False
        self._held: _HeldBox | None = None  # the last box the depth held up

    def update(self, depth: np.ndarray, detection: Detection | None, size_m: float, lane: np.ndarray,
               t_s: float) -> LeadEvidence:
        """One new frame: ``depth`` (H, W) m, the lead's ``detection`` and its size witness ``size_m``,
        the lane's centre ahead ((N, 2) z, y in the camera's frame), at ``t_s`` s."""
        c = self.config
        if detection is None:
            self.last = LeadEvidence(math.nan, math.nan, False, self._caught)
            return self.last
        points, upright = box_points(depth, detection.box, self.camera, self.camera_height_m)
        on_lane = in_lane(points, lane, c.lane_half_width_m)
        standing = points[on_lane & upright, 0]
        nearest = float(np.quantile(standing, c.nearest_quantile)) if len(standing) else math.nan
        # The share of the lane the box covers (floor or not) that stands at the box's distance.
        lane_z = points[on_lane, 0]
        support = float(np.mean(upright[on_lane] & (np.abs(lane_z - size_m) <= c.tolerance(size_m)))) \
            if len(lane_z) >= c.min_pixels and math.isfinite(size_m) else math.nan
        # A box the depth does not hold up; without a verdict (no size, too little lane) it is not caught by.
        unsupported = support < c.min_support
        # Since the last held-up box (None: none to compare with), did what stands stay, and did the box?
        held = self._held if self._held is not None and 0.0 <= t_s - self._held.t_s <= c.memory_s else None
        stood = None if held is None else self._stayed(nearest, held.nearest_m, t_s - held.t_s)
        boxed = None if held is None else self._stayed(size_m, held.size_m, t_s - held.t_s)
        jumped = False
        if unsupported and boxed is True and stood is False:
            self._moved = True  # what stood in the box moved away from it: the range sensors are attacked
        elif unsupported and stood is not None and boxed is not None:
            # The box moved further from where it was than what stands there did (by more than the size's
            # own noise, a row or two of the box): it left the car.
            jumped = abs(size_m - held.size_m) - abs(nearest - held.nearest_m) > c.jump_margin_m
        bare = support == 0.0 and not len(standing)  # the depth sees the bare floor where the box stands
        if unsupported and not self._moved and (jumped or bare):
            self._caught = True
        held_up = support >= c.min_support
        if held_up:
            self._caught = False  # the picture has gone: a next one must be caught again
            if math.isfinite(nearest):
                self._held = _HeldBox(t_s, nearest, size_m)
        # Once caught, a box the depth does not hold up (or cannot judge) is taken for the picture until a
        # box is held up again, unless what stands on the lane in it is nearer than it says (it errs safe).
        picture = self._caught and not held_up and not nearest <= size_m
        self.last = LeadEvidence(support, nearest, picture, self._caught)
        return self.last

    def _stayed(self, distance_m: float, then_m: float, elapsed_s: float) -> bool | None:
        """Whether ``distance_m`` is where it was (``then_m``) ``elapsed_s`` ago, as far as a car can have
        moved since (None: no distance now)."""
        if not math.isfinite(distance_m):
            return None
        return bool(abs(distance_m - then_m) <= self.config.jump_margin_m + self.config.closing_mps * elapsed_s)


@dataclass(frozen=True)
class _HeldBox:
    """The last box the depth held up: when, what stood nearest in it and its size's distance."""

    t_s: float
    nearest_m: float
    size_m: float
