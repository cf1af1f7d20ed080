"""The car ahead in the camera: the learned segmenter given a vehicle class.

The sign segmenter's network (:class:`~racf.controllers.segmenter_net.SignSegmenterNet`), trained on
racf's renders of a QCar 2 ahead in every paint, crosswise and at an angle
(``racf.experiments.detector.vehicle_train``; the shipped checkpoint is
``assets/checkpoints/vehicle-segmenter``). Its candidates are the components of the pixels it scores
a car's; the car ahead is the one that stands in the car's own lane: the candidate whose box holds
the bearing of the lane ``LANE_LOOKAHEAD_M`` ahead of it, where the map and the car's pose put it
(``Perception``'s map check, given the lane's bearing), the largest if several do.

Its box's height is the size witness: the box spans ``VEHICLE_BOX_HEIGHT_M`` of a QCar 2 seen from any
side (its width does not: a car at an angle shows its flank).
"""

from __future__ import annotations

from pathlib import Path

from racf.assets import asset_path
from racf.controllers.learned_detector import LearnedDetectorConfig, LearnedSignDetector
from racf.controllers.segmenter_net import SignSegmenterNet

__all__ = ["LearnedVehicleDetector", "shipped_vehicle_segmenter", "VEHICLE_BOX_HEIGHT_M"]


def shipped_vehicle_segmenter() -> Path:
    """The shipped checkpoint's directory."""
    return asset_path("checkpoints", "vehicle-segmenter")

#: How much of a QCar 2's height the segmenter's box spans, m: the car is 0.195 m tall to the top of
#: its LiDAR (its MJCF), and the box, from the net's half-resolution mask, 0.168 m of it (measured:
#: box height x depth / fy against the true depth of the car's rear, median over 1135 frames of the
#: four clean lead profiles; the box's top row and its bottom one are each about half a cell short).
VEHICLE_BOX_HEIGHT_M = 0.168


class LearnedVehicleDetector(LearnedSignDetector):
    """Finds cars with the vehicle segmenter (same interface as the sign detectors)."""

    #: Its boxes span the whole car, floor to roof: the size witness measures their height.
    outline = "vehicle"

    def __init__(self, config: LearnedDetectorConfig | None = None, checkpoint: Path | None = None,
                 net: SignSegmenterNet | None = None) -> None:
        if net is None and checkpoint is None:
            checkpoint = shipped_vehicle_segmenter()
        super().__init__(config or LearnedDetectorConfig(min_area_px=12), checkpoint, net)
