"""Whether a stop sign stands ahead: the witnesses of its existence, and the RACF vote over them.

A sticker changes the plate's colour, not its shape. Beside the two detectors (what the sign
*is*), the car holds two physical witnesses of *that* something stands there, and the map:

- **depth**: in the depth image, at the rows where a plate at the sign's height shows, a
  compact object (at most ``MAX_WIDTH_M`` across) standing free: the columns on both sides
  lie at least ``FREE_GAP_M`` further away (a picture on a wall has the wall beside it);
- **LiDAR**: the same test on the scan, where its plane meets the plate or the pole;
- **the map**: it lists a sign here (a prior the physical witnesses can outvote).

Each is read at one **hypothesis**, a place where a sign may stand: where the map puts its sign
when it lists one and something stands there; otherwise where a detector sees a stop sign
(a temporary sign, a sign moved off its map entry, a phantom).

:func:`vote` is RACF's cross-check: a sign stands when a physical witness (depth or LiDAR)
finds an object there *and* a semantic one (either detector, or the map) says it is a stop
sign. No single witness decides: a sticker that blinds both detectors leaves the map and the
plate; a removed sign leaves the map alone; a phantom leaves the detectors alone.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from racf.controllers.detector import Detection
from racf.controllers.distance import CameraModel

__all__ = ["ExistenceWitnesses", "Hypothesis", "free_standing", "depth_witness", "lidar_witness", "vote",
           "MAX_WIDTH_M", "FREE_GAP_M", "DEPTH_JUMP_M", "LIDAR_JUMP_M", "NO_WITNESSES"]

#: The widest object a sign's plate (0.10 m) or pole can be, m.
MAX_WIDTH_M = 0.16
#: How much further than the object what stands beside it must be, m.
FREE_GAP_M = 0.15
#: Neighbouring ranges further apart than this belong to different surfaces, m: the depth image's
#: columns (a few mm of noise at 2 m), and the A2M12's beams (centimetres, and a sweep's skew).
DEPTH_JUMP_M = 0.06
LIDAR_JUMP_M = 0.15
#: How many columns (beams) beside the object the free-space test reads on each side.
_BESIDE = 2


@dataclass(frozen=True)
class Hypothesis:
    """A place a sign may stand, seen from the car.

    Attributes:
        bearing_rad: from the camera's optical axis, left positive.
        depth_m: along the optical axis, m.
        tolerance_m: how far from ``depth_m`` the object may be found, m.
        half_width_rad: how far either side of the bearing it may be found.
        source: ``map`` (the map's entry), or ``detector`` (where a detector sees one).
        rows: the image rows the plate spans there (top, bottom), from the map's sign height
            or the detection's box.
    """

    bearing_rad: float
    depth_m: float
    tolerance_m: float
    half_width_rad: float
    source: str
    rows: tuple[int, int]


@dataclass(frozen=True)
class ExistenceWitnesses:
    """What the car holds on one step about whether a sign stands ahead (the evidence a defence
    that answers ``stands()`` reads, as ``PerceptionSample.witnesses``).

    Attributes:
        seen: per detector (the car's, then the second), whether it sees a stop sign this frame
            where the map lists one (a target the map does not list: anywhere).
        seen_depth_m: per detector, the depth of what it sees, m (NaN: nothing).
        detectors: per detector, whether it sees a stop sign at the hypothesis.
        depth: the depth witness found a compact, free-standing object there.
        lidar: the LiDAR witness did.
        mapped: the hypothesis is the map's entry (the map lists a sign there).
        depth_m: the object's camera depth, m (the depth witness's, else the LiDAR's; NaN: none).
        map_depth_m: the camera depth where the map puts its sign, m (NaN: it lists none ahead).
        source: where the hypothesis came from (``map``, ``detector``; empty: none).
    """

    seen: tuple[bool, ...]
    seen_depth_m: tuple[float, ...]
    detectors: tuple[bool, ...]
    depth: bool
    lidar: bool
    mapped: bool
    depth_m: float
    map_depth_m: float
    source: str

    def columns(self) -> dict[str, float]:
        """The witnesses as step-log columns (1.0 / 0.0)."""
        out = {f"wit_det{k}": float(v) for k, v in enumerate(self.detectors)}
        out |= {f"seen_det{k}": float(v) for k, v in enumerate(self.seen)}
        return out | {"wit_depth": float(self.depth), "wit_lidar": float(self.lidar), "wit_map": float(self.mapped),
                      "wit_depth_m": self.depth_m, "map_depth_m": self.map_depth_m}


NO_WITNESSES = ExistenceWitnesses((False, False), (math.nan, math.nan), (False, False), False, False, False, math.nan,
                                  math.nan, "")


def vote(witnesses: ExistenceWitnesses) -> bool:
    """RACF's existence vote: a physical witness and a semantic one agree that a sign stands."""
    physical = witnesses.depth or witnesses.lidar
    semantic = any(witnesses.detectors) or witnesses.mapped
    return bool(physical and semantic)


def free_standing(profile_m: np.ndarray, lateral: np.ndarray, centre: float, half_width: float,
                  expected_m: float, tolerance_m: float, jump_m: float = DEPTH_JUMP_M) -> float:
    """The range of a compact object standing free in a range profile, near a place; NaN if none.

    The profile splits into surfaces where neighbouring ranges jump; of the surfaces that reach
    into the place at the expected range, the one nearest that range that is at most
    ``MAX_WIDTH_M`` across with what lies beside it at least ``FREE_GAP_M`` further away.

    Args:
        profile_m: ranges along a row of the image (per column) or a scan (per beam), m; not
            finite or <= 0: no return.
        lateral: per entry, the lateral position per metre of range (columns: (cx - u) / fx;
            beams: the angle), monotonic.
        centre, half_width: where to look, in ``lateral``'s units.
        expected_m, tolerance_m: the range it should have.
        jump_m: neighbours further apart than this are different surfaces.
    """
    ranges = np.where(np.isfinite(profile_m) & (profile_m > 0), profile_m, np.inf)
    inside = np.flatnonzero((np.abs(lateral - centre) <= half_width) & (np.abs(ranges - expected_m) <= tolerance_m))
    if inside.size == 0:
        return math.nan
    # Surfaces: runs of neighbours whose ranges differ by less than a jump (no return to no return: a jump).
    with np.errstate(invalid="ignore"):
        breaks = np.flatnonzero(~(np.abs(np.diff(ranges)) < jump_m)) + 1
    starts, ends = np.concatenate([[0], breaks]), np.concatenate([breaks, [len(ranges)]]) - 1
    step = abs(float(lateral[1] - lateral[0]))  # one column's (beam's) width per metre
    best = math.nan
    for run in np.unique(np.searchsorted(breaks, inside, side="right")):
        lo, hi = int(starts[run]), int(ends[run])
        r = float(np.median(ranges[lo:hi + 1]))
        if abs(r - expected_m) > tolerance_m or lo < _BESIDE or hi > len(ranges) - 1 - _BESIDE:
            continue  # off the expected range, or cut by the edge (what is beside it is unseen)
        width = r * (abs(float(lateral[hi] - lateral[lo])) + step)
        beside = np.concatenate([ranges[lo - _BESIDE:lo], ranges[hi + 1:hi + 1 + _BESIDE]])
        if width <= MAX_WIDTH_M and bool(np.all(beside > r + FREE_GAP_M)) and not (
                abs(best - expected_m) <= abs(r - expected_m)):
            best = r
    return best


def depth_witness(depth: np.ndarray, camera: CameraModel, hypothesis: Hypothesis) -> float:
    """The depth witness at ``hypothesis``: the camera depth of a compact free-standing object in
    the rows the plate spans there, each column's median over them; NaN if none (or if the place
    lies outside the camera's view)."""
    if abs(hypothesis.bearing_rad) >= camera.half_hfov_rad:
        return math.nan
    depth = np.asarray(depth, np.float64)
    top, bottom = (int(np.clip(r, 0, depth.shape[0] - 1)) for r in hypothesis.rows)
    if bottom < top:
        return math.nan
    band = depth[top:bottom + 1]
    band = np.where(np.isfinite(band) & (band > 0), band, np.nan)
    with warnings.catch_warnings():  # a column with no return at all is NaN, as it should be
        warnings.simplefilter("ignore", RuntimeWarning)
        profile = np.nanmedian(band, axis=0)
    columns = np.arange(depth.shape[1], dtype=np.float64) + 0.5
    lateral = (camera.cx - columns) / camera.fx
    centre = math.tan(hypothesis.bearing_rad)
    half = abs(math.tan(hypothesis.bearing_rad + hypothesis.half_width_rad) - centre)
    return free_standing(profile, lateral, centre, half, hypothesis.depth_m, hypothesis.tolerance_m)


def lidar_witness(scan: np.ndarray, hypothesis: Hypothesis, camera_xy_m: tuple[float, float],
                  lidar_xy_m: tuple[float, float]) -> float:
    """The LiDAR witness at ``hypothesis``: the camera depth of a compact free-standing return
    (beam j at j x 2 pi / N, counter-clockwise from forward); NaN if none."""
    ranges = np.asarray(scan, np.float64)
    n = len(ranges)
    # The hypothesis in the LiDAR's frame (body axes; the camera looks along the body's x).
    x = camera_xy_m[0] + hypothesis.depth_m - lidar_xy_m[0]
    y = camera_xy_m[1] + hypothesis.depth_m * math.tan(hypothesis.bearing_rad) - lidar_xy_m[1]
    rng, angle = math.hypot(x, y), math.atan2(y, x)
    # Unwrapped around the hypothesis: the beams within a half-turn of it, in angle order.
    offsets = np.arange(-(n // 2), n - n // 2)
    index = (int(round(angle / (2 * math.pi / n))) + offsets) % n
    lateral = (index * (2 * math.pi / n) - angle + math.pi) % (2 * math.pi) - math.pi + angle
    half = hypothesis.half_width_rad * hypothesis.depth_m / max(rng, 1e-6) + 2 * math.pi / n
    found = free_standing(ranges[index], lateral, angle, half, rng, hypothesis.tolerance_m, LIDAR_JUMP_M)
    if not math.isfinite(found):
        return math.nan
    return found * math.cos(angle) + lidar_xy_m[0] - camera_xy_m[0]  # back to the camera's depth


def detection_hypothesis(detection: Detection, depth_m: float, camera: CameraModel) -> Hypothesis:
    """Where a detection puts a sign: at its box's bearing and its depth, in its rows' middle half."""
    x0, y0, x1, y1 = detection.box
    quarter = (y1 - y0) / 4
    left, right = camera.bearing(x0 - 0.5), camera.bearing(x1 - 0.5)
    return Hypothesis(camera.bearing(detection.centroid[0]), depth_m, 0.25, abs(left - right) / 2 + math.radians(1),
                      "detector", (int(y0 + quarter), int(math.ceil(y1 - 1 - quarter))))
