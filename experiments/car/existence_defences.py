"""Defences that say whether a stop sign stands, not only how far it is.

The contract (``racf.controllers.estimators.DistanceEstimator``) gains one optional answer: a
defence with ``existence = True`` gets the existence stage's witnesses with each sample
(``PerceptionSample.witnesses``) and answers ``stands()`` after each ``estimate``: True or
False, or None to defer to the detector. The braker confirms its track on that verdict and
brakes on the distance ``estimate`` returns. A user's defence takes part the same way.

- ``vote``: RACF's existence vote (:func:`racf.controllers.existence.vote`) over the two detectors,
  the depth and LiDAR witnesses and the map; its distance is an inner defence's (ODCA by
  default) while the car's detector sees the sign, else the physical witnesses' depth (where
  they are blind at the map's sign, the map's). Where the depth at the map's sign is caught
  moving, the map's: the inner defence reads that same depth;
- ``detectors_or``: the two detectors OR-ed (a sign stands when either sees it); its distance
  is the inner defence's, else the depth at the second detector's detection;
- ``map_only``: stop at every line the map lists (a sign stands whenever the map lists one
  ahead); its distance is where the map puts the sign from the car's own pose.

Detector-only (what every defence did before) is any defence without ``existence``.
"""

from __future__ import annotations

import math

from racf.controllers import PerceptionSample
from racf.controllers.existence import NO_WITNESSES, ExistenceWitnesses, vote
from racf.controllers.lead_existence import LeadEvidence

__all__ = ["ExistenceVote", "DetectorsOr", "MapOnly"]


class _Existence:
    """What the three share: an inner defence for the distance, the witnesses, the verdict."""

    name = "existence"
    existence = True
    second_detector: str | None = "learned"

    def __init__(self, inner: str = "odca") -> None:
        from racf.experiments.car.estimators import make_estimator

        self.inner_name = inner
        self.inner = make_estimator(inner, {})
        self._stands: bool | None = None
        self._witnesses = NO_WITNESSES
        self._carried = math.nan

    @property
    def n_parameters(self) -> int:
        return int(getattr(self.inner, "n_parameters", 0))

    @property
    def n_frozen_parameters(self) -> int:
        return int(getattr(self.inner, "n_frozen_parameters", 0))

    def use_calibration(self, calibration) -> None:
        configure = getattr(self.inner, "use_calibration", None)
        if callable(configure):
            configure(calibration)

    def reset(self) -> None:
        self.inner.reset()
        self._stands = None
        self._witnesses = NO_WITNESSES
        self._carried = math.nan

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        if isinstance(sample.witnesses, LeadEvidence):  # the car ahead: no map lists it
            return self.lead_estimate(sample, speed_mps, dt, yaw_rate_radps)
        d = float(self.inner.estimate(sample, speed_mps, dt, yaw_rate_radps=yaw_rate_radps))
        self._witnesses = sample.witnesses if sample.witnesses is not None else NO_WITNESSES
        self._stands = self.verdict(self._witnesses)
        if not math.isfinite(d) or self.distrusts_inner(self._witnesses):
            d = self.fallback_distance(self._witnesses)
        # With no witness left (the sign went out of the picture on a bend), the last distance is
        # carried on by odometry, as ODCA's kinematic branch does: the braker decides whether the
        # track still stands (the target expected in view, within its timeout).
        self._carried = d if math.isfinite(d) else self._carried - max(0.0, speed_mps) * dt
        return self._carried

    def verdict(self, witnesses: ExistenceWitnesses) -> bool:
        raise NotImplementedError

    def lead_estimate(self, sample: PerceptionSample, closing_mps: float, dt: float, yaw_rate_radps: float) -> float:
        """The distance to the car ahead (the sample's witnesses: ``LeadEvidence``): the inner defence's."""
        return float(self.inner.estimate(sample, closing_mps, dt, yaw_rate_radps=yaw_rate_radps))

    def fallback_distance(self, witnesses: ExistenceWitnesses) -> float:
        """The distance when the inner defence has none (the car's detector does not see the sign)."""
        return math.nan

    def distrusts_inner(self, witnesses: ExistenceWitnesses) -> bool:
        """Whether the witnesses show the inner defence's distance is not to be used this step."""
        return False

    def stands(self) -> bool | None:
        return self._stands

    def diagnostics(self) -> dict[str, float]:
        out = dict(self.inner.diagnostics())
        if self._stands is not None:
            out |= self._witnesses.columns() | {"stands": float(self._stands)}
        return out

    def would_pass(self, **kwargs) -> bool:
        return self.inner.would_pass(**kwargs)


class _WithSecondDetector(_Existence):
    """An existence defence that reads a second detector beside the car's (an option)."""

    def __init__(self, inner: str = "odca", second_detector: str = "learned") -> None:
        super().__init__(inner)
        self.second_detector = second_detector


class ExistenceVote(_WithSecondDetector):
    """RACF's vote: a physical witness (depth, LiDAR) and a semantic one (either detector, the map).

    ``lead_check``: whether the vote acts on the car ahead's existence check (a box taken for a picture
    of a car is no witness). Off by default: on battery ``racf-6`` it cut needless hard brakes under a
    phantom car but cost collisions under the patch and the frustum spoof with the depth (the stored
    result ``racf-6-vote-lead-check``), and a defence that adds collisions is worse than none.
    """

    name = "vote"

    def __init__(self, inner: str = "odca", second_detector: str = "learned", lead_check: bool = False) -> None:
        super().__init__(inner, second_detector)
        self.lead_check = bool(lead_check)
        self._in_picture = False  # the car ahead's box was a picture on the last step
        self._lead_carried = math.nan

    def verdict(self, witnesses: ExistenceWitnesses) -> bool:
        return vote(witnesses)

    def fallback_distance(self, witnesses: ExistenceWitnesses) -> float:
        """The physical witnesses' depth; where the depth is blind at the map's sign, the map's, and
        where it is caught moving there, the map's whatever it reads."""
        if witnesses.mapped and (witnesses.moving or (witnesses.blind and not math.isfinite(witnesses.depth_m))):
            return witnesses.map_depth_m
        return witnesses.depth_m

    def distrusts_inner(self, witnesses: ExistenceWitnesses) -> bool:
        return witnesses.mapped and witnesses.moving  # the inner defence reads the depth that was caught

    def lead_estimate(self, sample: PerceptionSample, closing_mps: float, dt: float, yaw_rate_radps: float) -> float:
        """The inner defence's distance, unless ``lead_check`` is on and the box is taken for a picture of
        a car. Then the box is no witness (the inner defence reads its size and the depth in its mask): the distance is the
        nearer of the LiDAR's track and the nearest upright thing on the lane in the box, else the
        last distance carried by the closing speed. The inner defence does not read the picture, and
        starts afresh when it goes (what it carried from before it is stale)."""
        evidence = sample.witnesses
        if evidence.picture and self.lead_check:
            self._in_picture = True
            seen = [v for v in (sample.lidar_m, evidence.nearest_m) if math.isfinite(v)]
            d = min(seen) if seen else self._lead_carried - closing_mps * dt
        else:
            if self._in_picture:
                self.inner.reset()
                self._in_picture = False
            d = float(self.inner.estimate(sample, closing_mps, dt, yaw_rate_radps=yaw_rate_radps))
        self._lead_carried = d
        return d

    def reset(self) -> None:
        super().reset()
        self._in_picture = False
        self._lead_carried = math.nan


class DetectorsOr(_WithSecondDetector):
    """The two detectors OR-ed: a sign stands where either sees one (the map checks both)."""

    name = "detectors_or"

    def verdict(self, witnesses: ExistenceWitnesses) -> bool:
        return any(witnesses.seen)

    def fallback_distance(self, witnesses: ExistenceWitnesses) -> float:
        return witnesses.seen_depth_m[-1]


class MapOnly(_Existence):
    """Stop at every line the map lists: a sign stands whenever the map lists one ahead."""

    name = "map_only"
    second_detector = None

    def __init__(self, inner: str = "raw") -> None:
        super().__init__(inner)

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        super().estimate(sample, speed_mps, dt, yaw_rate_radps)
        return self._witnesses.map_depth_m  # the map's place, never a sensor's

    def verdict(self, witnesses: ExistenceWitnesses) -> bool:
        return math.isfinite(witnesses.map_depth_m)
