"""Whether a stop sign stands ahead: the witnesses of its existence, and the RACF vote over them.

A sticker changes the plate's colour, not its shape. Beside the two detectors (what the sign
*is*), the car holds two physical witnesses of *that* something stands there, and the map:

- **depth**: in the depth image, at the rows where a plate at the sign's height shows, a run of
  columns a plate's width at one range with open space over and under it but for its pole (a
  picture on a wall has the wall over it and under it);
- **LiDAR**: a compact return with open space seen around it, where its plane meets the plate or
  the pole (it stands in for the depth where the depth is blind);
- **the map**: it lists a sign here (a prior the physical witnesses can outvote).

Each is read at one **hypothesis**, a place where a sign may stand: where the map puts its sign
when it lists one and something stands there; otherwise where a detector sees a stop sign
(a temporary sign, a sign moved off its map entry, a phantom).

:func:`vote` is RACF's cross-check: a sign stands when a physical witness (the depth; where
the depth is blind, the LiDAR or the map) finds an object there *and* a semantic one (either
detector, or the map) says it is a stop sign. No single witness decides: a sticker that blinds both detectors leaves the map and the
plate; a removed sign leaves the map alone; a phantom leaves the detectors alone.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from racf.controllers.detector import Detection
from racf.controllers.distance import CameraModel

__all__ = ["ExistenceWitnesses", "Hypothesis", "free_standing", "detection_hypothesis", "depth_witness", "depth_hole",
           "lidar_witness", "vote", "PLATE_HALF_WIDTH_M", "OPEN_GAP_M", "LIDAR_PLATE_RADIUS_M", "CLEAR_RADIUS_M", "NO_WITNESSES"]

#: Half a plate's width, with the depth image's noise (millimetres), m.
PLATE_HALF_WIDTH_M = 0.06
#: Over and under a free plate (but for its pole), what the camera sees lies this much further, m.
OPEN_GAP_M = 0.10
#: How far a sign's own LiDAR returns reach from its centre: the plate's half-width (0.05) and the
#: pole behind it, with the A2M12's noise (centimetres, and a sweep's skew), m.
LIDAR_PLATE_RADIUS_M = 0.12
#: Around a free-standing sign, nothing else within this radius of its centre, m (a wall panel
#: the size of a poster, 0.24 m, reaches past it from either edge of the picture).
CLEAR_RADIUS_M = 0.25
#: Returns this far beyond an object's radius still count as its own (its centre is estimated), m.
_NOISE_M = 0.03


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
            and the car's camera height, or the detection's box.
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
        blind: the depth image has no return at all in part of the place (a real one has returns
            from whatever stands there or behind it): the camera's depth is blinded there.
        mapped: the hypothesis is the map's entry (the map lists a sign there).
        depth_m: the object's camera depth, m (the depth witness's, else the LiDAR's; NaN: none).
        map_depth_m: the camera depth the map's sign will have at its line plus the route's distance to
            that line, from the car's own localisation, m (NaN: the map lists none ahead).
        source: where the hypothesis came from (``map``, ``detector``; empty: none).
        moving: what the depth shows at the map's place runs along the camera's ray as no standing
            thing does (:mod:`racf.controllers.static_world`): the depth there is outvoted.
    """

    seen: tuple[bool, ...]
    seen_depth_m: tuple[float, ...]
    detectors: tuple[bool, ...]
    depth: bool
    lidar: bool
    blind: bool
    mapped: bool
    depth_m: float
    map_depth_m: float
    source: str
    moving: bool = False

    def columns(self) -> dict[str, float]:
        """The witnesses as step-log columns (1.0 / 0.0)."""
        out = {f"wit_det{k}": float(v) for k, v in enumerate(self.detectors)}
        out |= {f"seen_det{k}": float(v) for k, v in enumerate(self.seen)}
        return out | {"wit_depth": float(self.depth), "wit_lidar": float(self.lidar), "wit_blind": float(self.blind), "wit_map": float(self.mapped),
                      "wit_moving": float(self.moving), "wit_depth_m": self.depth_m, "map_depth_m": self.map_depth_m}


NO_WITNESSES = ExistenceWitnesses((False, False), (math.nan, math.nan), (False, False), False, False, False, False,
                                  math.nan, math.nan, "")


def vote(witnesses: ExistenceWitnesses) -> bool:
    """RACF's existence vote: a physical witness and a semantic one agree that a sign stands.

    The depth image is the physical witness. Where it is blind (no return at all where the plate
    would show) or caught moving (what it shows at the map's place runs along the ray as no
    standing thing does), the LiDAR stands in for it (alone, the A2M12's sparse, often dropped
    beams make empty space out of a wall seen obliquely and would pass a poster), and where the
    map lists a sign there, the map is not outvoted: only a sensor that sees through the place,
    and holds still while it does, can say that nothing stands in it."""
    unreliable = witnesses.blind or witnesses.moving
    physical = witnesses.depth or (unreliable and (witnesses.lidar or witnesses.mapped))
    semantic = any(witnesses.detectors) or witnesses.mapped
    return bool(physical and semantic)


def free_standing(profile_m: np.ndarray, lateral: np.ndarray, centre: float, half_width: float,
                  expected_m: float, tolerance_m: float, radius_m: float = LIDAR_PLATE_RADIUS_M) -> float:
    """The range of a compact object standing free in a range profile, near a place; NaN if none.

    The profile's returns are points in the plane (across, range). An object is compact and
    free when the returns within ``radius_m`` of it hold nothing else within ``CLEAR_RADIUS_M``:
    a plate on its pole has open space around it, a picture on a wall has the wall beside it,
    however obliquely it is seen. Of the returns at the place and the expected range, the
    nearest such object counts.

    Args:
        profile_m: ranges along a row of the image (per column) or a scan (per beam), m; not
            finite or <= 0: no return.
        lateral: per entry, the lateral position per metre of range (columns: (cx - u) / fx;
            beams: the angle), monotonic.
        centre, half_width: where to look, in ``lateral``'s units.
        expected_m, tolerance_m: the range it should have.
        radius_m: how far from its centre the object's own returns reach (its half-size and the
            sensor's noise), m.
    """
    ranges = np.where(np.isfinite(profile_m) & (profile_m > 0), profile_m, np.inf)
    seen = np.isfinite(ranges)
    across, along = lateral[seen] * ranges[seen], ranges[seen]
    inside = np.flatnonzero(seen & (np.abs(lateral - centre) <= half_width) & (np.abs(ranges - expected_m) <= tolerance_m))
    for k in inside[np.argsort(ranges[inside])]:  # the nearest first: what stands in front
        x, z = lateral[k] * ranges[k], ranges[k]
        # The space around it must be in view on both sides, or what is beside it is unseen.
        if not (lateral[seen].min() * z < x - CLEAR_RADIUS_M and lateral[seen].max() * z > x + CLEAR_RADIUS_M):
            continue
        cx, cz = x, z
        for _ in range(2):  # from its nearest return to its centre (an oblique plate's nearest is an edge)
            own = np.hypot(across - cx, along - cz) <= radius_m
            cx, cz = float(np.mean(across[own])), float(np.mean(along[own]))
        distance = np.hypot(across - cx, along - cz)
        # Open space must be seen: every ray passing beside it came back (from further away; a ray
        # with no return, which a LiDAR drops often, shows nothing either way).
        beside = (np.abs(lateral * cz - cx) <= CLEAR_RADIUS_M) & (np.abs(lateral * cz - cx) > radius_m)
        crowded = np.any((distance > radius_m + _NOISE_M) & (distance <= CLEAR_RADIUS_M))
        if not crowded and bool(np.all(seen[beside])):
            return cz
    return math.nan


def depth_witness(depth: np.ndarray, camera: CameraModel, hypothesis: Hypothesis) -> float:
    """The depth witness at ``hypothesis``: the camera depth of a plate standing free there; NaN if none
    (or if the place lies outside the camera's view).

    A plate is a run of columns, at most a plate's width (``PLATE_HALF_WIDTH_M`` either side) at
    one range in the plate's middle rows, with open space above it (a sign's plate has air over
    it; a picture on a wall has the wall) and below it but for its thin pole: there the depth
    lies at least ``OPEN_GAP_M`` further in most of its columns."""
    profile = _depth_profile(depth, camera, hypothesis)
    if profile is None:
        return math.nan
    values, lateral, centre, half = profile
    ranges = np.where(np.isfinite(values), values, np.inf)
    top, bottom = hypothesis.rows
    height = max(bottom - top, 2)
    above = (int(top - 0.6 * height), int(top - 0.15 * height))
    below = (int(math.ceil(bottom + 0.15 * height)), int(math.ceil(bottom + 0.6 * height)))
    if above[0] < 0 or below[1] >= depth.shape[0]:
        return math.nan  # what is over or under it is out of the picture: unseen
    inside = np.flatnonzero((np.abs(lateral - centre) <= half) & (np.abs(ranges - hypothesis.depth_m)
                                                                   <= hypothesis.tolerance_m))
    tried: set[tuple[int, ...]] = set()
    for k in inside[np.argsort(np.abs(ranges[inside] - hypothesis.depth_m))]:
        r = ranges[k]
        with np.errstate(invalid="ignore"):
            columns = np.flatnonzero((np.abs((lateral - lateral[k]) * r) <= PLATE_HALF_WIDTH_M)
                                     & (np.abs(ranges - r) <= PLATE_HALF_WIDTH_M))
        if len(columns) < 2 or tuple(columns) in tried:
            continue
        tried.add(tuple(columns))
        plate = float(np.median(ranges[columns]))
        if (_open_share(depth, above, columns, plate) >= 0.8
                and _open_share(depth, below, columns, plate) >= 0.6):
            return plate
    return math.nan


def _open_share(depth: np.ndarray, rows: tuple[int, int], columns: np.ndarray, plate_m: float) -> float:
    """The share of ``columns`` where, over ``rows``, the depth lies ``OPEN_GAP_M`` beyond the plate."""
    block = np.asarray(depth[rows[0]:rows[1] + 1, columns], np.float64)
    block = np.where(np.isfinite(block) & (block > 0), block, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        nearest = np.nanmin(block, axis=0) if block.size else np.full(len(columns), np.nan)
    return float(np.mean(nearest > plate_m + OPEN_GAP_M))


def depth_hole(depth: np.ndarray, camera: CameraModel, hypothesis: Hypothesis) -> bool:
    """Whether the depth image has no return at all in some column where the hypothesis's plate would
    show: the camera blinded there (a real depth image has returns from whatever stands behind)."""
    profile = _depth_profile(depth, camera, hypothesis)
    if profile is None:
        return False
    values, lateral, centre, half = profile
    return bool(np.any(~np.isfinite(values[np.abs(lateral - centre) <= half])))


def _depth_profile(depth: np.ndarray, camera: CameraModel, hypothesis: Hypothesis):
    """(each column's median depth over the plate's middle rows, lateral per metre, centre,
    half-width); None when the place lies outside the camera's view."""
    if abs(hypothesis.bearing_rad) >= camera.half_hfov_rad:
        return None
    depth = np.asarray(depth, np.float64)
    top, bottom = hypothesis.rows
    quarter = (bottom - top) / 5
    top, bottom = (int(np.clip(round(r), 0, depth.shape[0] - 1)) for r in (top + quarter, bottom - quarter))
    if bottom < top:
        return None
    band = depth[top:bottom + 1]
    band = np.where(np.isfinite(band) & (band > 0), band, np.nan)
    with warnings.catch_warnings():  # a column with no return at all is NaN, as it should be
        warnings.simplefilter("ignore", RuntimeWarning)
        profile = np.nanmedian(band, axis=0)
    columns = np.arange(depth.shape[1], dtype=np.float64) + 0.5
    lateral = (camera.cx - columns) / camera.fx
    centre = math.tan(hypothesis.bearing_rad)
    return profile, lateral, centre, abs(math.tan(hypothesis.bearing_rad + hypothesis.half_width_rad) - centre)


def lidar_witness(scan: np.ndarray, hypothesis: Hypothesis, camera_xy_m: tuple[float, float],
                  lidar_xy_m: tuple[float, float]) -> float:
    """The LiDAR witness at ``hypothesis``: the camera depth of a compact free-standing return
    (beam j at j x 2 pi / N, counter-clockwise from forward); NaN if none."""
    ranges, lateral, angle, half, rng = _scan_around(scan, hypothesis, camera_xy_m, lidar_xy_m)
    found = free_standing(ranges, lateral, angle, half, rng, hypothesis.tolerance_m, LIDAR_PLATE_RADIUS_M)
    if not math.isfinite(found):
        return math.nan
    return found * math.cos(angle) + lidar_xy_m[0] - camera_xy_m[0]  # back to the camera's depth


def _scan_around(scan: np.ndarray, hypothesis: Hypothesis, camera_xy_m: tuple[float, float],
                 lidar_xy_m: tuple[float, float]):
    """The scan unwrapped around the hypothesis (ranges and angles in angle order), its angle,
    the window's half-width and its range from the LiDAR."""
    ranges = np.asarray(scan, np.float64)
    n = len(ranges)
    # The hypothesis in the LiDAR's frame (body axes; the camera looks along the body's x).
    x = camera_xy_m[0] + hypothesis.depth_m - lidar_xy_m[0]
    y = camera_xy_m[1] + hypothesis.depth_m * math.tan(hypothesis.bearing_rad) - lidar_xy_m[1]
    rng, angle = math.hypot(x, y), math.atan2(y, x)
    offsets = np.arange(-(n // 2), n - n // 2)
    index = (int(round(angle / (2 * math.pi / n))) + offsets) % n
    lateral = (index * (2 * math.pi / n) - angle + math.pi) % (2 * math.pi) - math.pi + angle
    half = hypothesis.half_width_rad * hypothesis.depth_m / max(rng, 1e-6) + 2 * math.pi / n
    return ranges[index], lateral, angle, half, rng


def detection_hypothesis(detection: Detection, depth_m: float, camera: CameraModel, rows: tuple[int, int]) -> Hypothesis:
    """Where a detection puts a sign: at its box's bearing and its depth, over ``rows`` (where a sign
    of the map's build shows at that depth: a sticker may hide part of the plate from the detector)."""
    x0, _, x1, _ = detection.box
    left, right = camera.bearing(x0 - 0.5), camera.bearing(x1 - 0.5)
    return Hypothesis(camera.bearing(detection.centroid[0]), depth_m, 0.25, abs(left - right) / 2 + math.radians(1),
                      "detector", rows)
