"""Whether a car stands ahead: the witnesses of its existence, for the same vote as a stop sign's.

A picture of a car (a phantom: projected on the road, shown on a screen; Nassi et al., CCS 2020)
fools the camera's detector, not the range sensors. A car's rear is an upright surface standing
free: in the depth image, the pixels of the detector's mask hold a run of rows at one range, as
many rows as a car's height spans there, with open space over it (a car's roof, then what lies
beyond it). A picture on the road holds the road, whose range changes with every row; one beside
a wall holds the wall, which has more wall over it; a picture over a real car holds that car. The witnesses are then the sign's
(:class:`~racf.controllers.existence.ExistenceWitnesses`), and RACF's vote
(:func:`~racf.controllers.existence.vote`) reads them unchanged: the vehicle detector is the
semantic witness, the upright surface the physical one (where the depth is blind, the LiDAR's
track stands in), and no map lists a car.
"""

from __future__ import annotations

import math

import numpy as np

from racf.controllers.distance import CameraModel
from racf.controllers.existence import ExistenceWitnesses
from racf.controllers.perception import PerceptionSample
from racf.controllers.vehicle_detector import VEHICLE_BOX_HEIGHT_M

__all__ = ["upright_range", "lead_witnesses", "UPRIGHT_BAND", "UPRIGHT_MIN_M", "UPRIGHT_SHARE", "OPEN_ABOVE_M", "BLIND_SHARE",
           "REAR_WIDTH_M"]

#: Pixels within this share of a range, or ``UPRIGHT_MIN_M``, are at that range: the depth's noise, and
#: a QCar 2's stepped rear (bumper, body, roof-top LiDAR), 0.15 m deep from bumper to roof.
UPRIGHT_BAND = 0.075
UPRIGHT_MIN_M = 0.08
#: An upright surface at range r spans at least this share of a car's rear's rows, in at least this
#: share of its columns (a wall's edge is tall and narrow; the road is wide and low).
UPRIGHT_SHARE = 0.5
#: A QCar 2's rear width, m (its body; the size witness reads the box's height, which no angle widens).
REAR_WIDTH_M = 0.192
#: Over a car's rear the depth lies at least this much further in most of its columns, m.
OPEN_ABOVE_M = 0.10
#: The depth is blind at the car when this share of its mask has no return.
BLIND_SHARE = 0.5


def upright_range(depth: np.ndarray, mask: np.ndarray, camera: CameraModel) -> float:
    """The nearest range at which the mask's pixels hold an upright surface a car's height tall with
    open space over it, m; NaN if none (the mask holds the road, a wall, or nothing with a return).
    Close up, where the picture cuts the car, the surface need fill only what the mask spans."""
    depth = np.asarray(depth, np.float64)
    rows, cols = np.nonzero(mask)
    if rows.size < 4:
        return math.nan
    extent_rows, extent_cols = rows.max() - rows.min() + 1, cols.max() - cols.min() + 1
    d = depth[rows, cols]
    seen = np.isfinite(d) & (d > 0.05)
    rows, cols, d = rows[seen], cols[seen], d[seen]
    if d.size < 4:
        return math.nan
    fy = camera.fy if camera.fy is not None else camera.fx
    step = math.log1p(0.02)  # candidate ranges 2 % apart
    for b in np.unique(np.floor(np.log(d) / step)):  # the nearest first: what stands in front
        centre = math.exp((b + 0.5) * step)
        near = np.abs(d - centre) <= max(UPRIGHT_BAND * centre, UPRIGHT_MIN_M)
        r = float(np.median(d[near]))
        # A car's rear at r, in pixels, as far as the mask shows it.
        tall = min(fy * VEHICLE_BOX_HEIGHT_M / r, extent_rows)
        wide = min(camera.fx * REAR_WIDTH_M / r, extent_cols)
        columns, spans = np.unique(cols[near], return_counts=True)
        upright = columns[spans >= UPRIGHT_SHARE * tall]
        if upright.size >= UPRIGHT_SHARE * wide:
            keep = near & np.isin(cols, upright)
            if _open_above(depth, rows[keep], cols[keep], r, tall):
                return r
    return math.nan


def _open_above(depth: np.ndarray, rows: np.ndarray, cols: np.ndarray, r: float, tall: float) -> bool:
    """Whether over the surface's top, in most of its columns, the depth lies ``OPEN_ABOVE_M`` further."""
    reach = max(3, int(round(0.3 * tall)))
    open_columns = []
    for c in np.unique(cols):
        top = int(rows[cols == c].min())
        above = depth[max(top - reach, 0):max(top - 1, 0), c]
        above = above[np.isfinite(above) & (above > 0.05)]
        if above.size:
            open_columns.append(bool(above.min() > r + OPEN_ABOVE_M))
    return bool(open_columns) and float(np.mean(open_columns)) >= 0.6


def lead_witnesses(sample: PerceptionSample, depth: np.ndarray, camera: CameraModel) -> ExistenceWitnesses:
    """The witnesses of the car ahead on one frame: the detector (``sample.detection``), the upright
    surface in its mask, the depth's blindness there and the LiDAR's track (``sample.lidar_m``)."""
    detection = sample.detection
    upright, blind = math.nan, False
    if detection is not None:
        mask = np.asarray(detection.mask, bool)
        upright = upright_range(depth, mask, camera)
        values = np.asarray(depth, np.float64)[mask]
        blind = bool(values.size and np.mean(~(np.isfinite(values) & (values > 0.05))) >= BLIND_SHARE)
    detected = detection is not None
    return ExistenceWitnesses((detected,), (sample.d_meas,), (detected,), math.isfinite(upright),
                              math.isfinite(sample.lidar_m), blind, False, upright, math.nan,
                              "detector" if detected else "")
