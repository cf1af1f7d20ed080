"""The supervisor of a static target (a stop sign, a person, a crate): its place vouched by the car's
own witnesses, carried until the car has stood before it, and a stop rule that holds the car short of
its line.

It reads one published track of a static kind (``TargetTrack``: the car's own sign loop publishes its
stop sign's, a plug-in stage its person's) and nothing else of its publisher. The target never moves,
so between vouches only the car's travel moves it: its near end falls by the travel at the bound on
the car's true speed (:class:`racf.controllers.speed.SpeedBound`), with the encoder's error.

- **Vouched** when two of its witnesses agree on it (the depth, the LiDAR's track of its post, the
  size witness, where the map and the car's pose put it) for ``confirm_frames`` frames, at the nearest
  of those that agree; or by a range reading that lies where the carried target is. A served or
  defended distance is never a witness: it is what the supervisor checks (a served lie outvoted).
  A target the map does not list and no detection came before stays unvouched until two range
  witnesses confirm it.
- **The stop rule.** While a target is carried, a car faster than stopping ``margin_m`` short of its
  line allows (:func:`~.envelope.safe_speed` on the room, the target standing) is told to stop (cap 0).
  The room is the car's own distance along its route to the line where the map lists the target (its
  pose estimate and the map: in a bend a camera's distance to a sign beside the road is no distance
  along it), less what that may be off (``route_error_m``, A6). A target the map does not list is
  placed on the route by the car itself: each vouched reading less delta, along its bearing from the
  car's pose, projected on the route, less the line's distance before the target (the farthest of
  those places is carried: each is a lower bound). Without a bearing or a route, the carried near end
  less the line's camera depth. It never raises what the car's braker or another stage says: it only
  adds a limit.
- **Done** once the car has stood before the line (the stop the sign asks for), or the car's loop
  publishes its next target.

Its columns are prefixed with the kind it supervises (``sup_sign_*``).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from racf.controllers.speed import SpeedBound
from racf.experiments.car.stage import CarStage, CarView, StageColumn, StageContext, StageLimit, TargetTrack
from racf.experiments.car.supervisor.envelope import Envelope, safe_speed
from racf.experiments.car.supervisor.vouch import agree_m

__all__ = ["StaticSupervisor", "static_supervisor", "STOOD_MPS"]

#: The car stood before the line once the bound on its speed fell under this, m/s.
STOOD_MPS = 0.02
#: Frames two witnesses must agree on a target before it is first vouched.
CONFIRM_FRAMES = 3


def _columns(kind: str) -> tuple[StageColumn, ...]:
    p = f"sup_{kind}_"
    return (StageColumn(f"{p}vouched", "bool", f"supervisor of the {kind}: its place is vouched this step"),
            StageColumn(f"{p}carried", "bool", f"supervisor of the {kind}: a {kind} is carried (vouched, not yet "
                                               "stood before)"),
            StageColumn(f"{p}near", "m", f"supervisor of the {kind}: the nearest it can be, camera distance (NaN: "
                                         "none)"),
            StageColumn(f"{p}outvoted", "bool", f"supervisor of the {kind}: the defended distance lay farther than "
                                                "the vouched place allows: the car's own witnesses outvoted it"),
            StageColumn(f"{p}stop", "bool", f"supervisor of the {kind}: the car was faster than stopping before its "
                                            "line allows: told to stop"),
            StageColumn(f"{p}cap", "m/s", f"supervisor of the {kind}: its speed cap (inf: none)"))


class StaticSupervisor(CarStage):
    """Runtime assurance over a published static target's track (see the module docstring).

    Args:
        context: the car's build.
        envelope: the guarantee's assumptions (the target's a_max is moot: it stands).
    """

    name = "static_supervisor"
    supervises = "sign"
    stands_in = False

    def __init__(self, context: StageContext, envelope: Envelope | None = None) -> None:
        super().__init__(context)
        self.envelope = envelope if envelope is not None else Envelope()
        self.speed_bound = SpeedBound(self.envelope.odometry_error)
        self._camera_xy = (float(context.camera_xy_m[0]), float(context.camera_xy_m[1]))
        self._bumper_m = float(context.bumper_ahead_of_camera_m)
        self._prefix = f"sup_{self.supervises}_"
        self.reset()

    def reset(self) -> None:
        self._forget(None)
        self.speed_bound.reset()

    def _forget(self, index) -> None:
        """Starts on target ``index`` (None: none yet): nothing carried, vouched, stood before or seen."""
        self.near_m = self.far_m = self.line_s = math.nan
        self.index, self.done, self.agreed, self.seen = index, False, 0, False

    @property
    def held(self) -> bool:
        return math.isfinite(self.near_m)

    def step(self, view: CarView) -> StageLimit:
        track: TargetTrack | None = view.tracks.get(self.supervises)
        bound = self.speed_bound.step(view.speed_mps, view.dt)
        if track is None:
            return self._said(math.inf, False, False, False)
        if track.index != self.index:  # the car's next target: what was carried is behind it
            self._forget(track.index)
        e = self.envelope
        if self.held:  # a standing target comes nearer by the car's travel only
            self.near_m -= bound * view.dt  # the far end stays: an upper bound, for continuity only
        vouched = self._vouch(track)
        if math.isfinite(vouched):
            self.near_m = vouched - e.delta_m if not self.held else max(self.near_m, vouched - e.delta_m)
            self.far_m = min(self.far_m, vouched + e.delta_m) if math.isfinite(self.far_m) else vouched + e.delta_m
            placed = self._line_on_route(view, track, vouched - e.delta_m)
            self.line_s = placed if not math.isfinite(self.line_s) else max(self.line_s, placed)
        self.seen = self.seen or bool(track.detected)
        if not self.held or self.done:
            return self._said(math.inf, math.isfinite(vouched), False, False)
        room = track.line_m if math.isfinite(track.line_m) else self._room_unlisted(view, track)
        if bound < STOOD_MPS and room > -e.margin_m:
            self.done = True  # the car stood before the line: the stop the target asks for is made
            return self._said(math.inf, math.isfinite(vouched), False, False)
        outvoted = math.isfinite(track.distance_m) and track.distance_m > self.far_m + agree_m(self.far_m)
        outvoted = outvoted or (not math.isfinite(track.distance_m) and math.isfinite(vouched))
        # The room along the route is the car's own (its pose against the map): less what that may be off (A6).
        stop = bound > safe_speed(room - e.route_error_m, 0.0, e)
        return self._said(0.0 if stop else math.inf, math.isfinite(vouched), outvoted, stop)

    def _line_on_route(self, view: CarView, track: TargetTrack, depth_m: float) -> float:
        """Where the line of an unlisted target ``depth_m`` ahead (the camera's axis) at its bearing lies
        along the route, m of arclength (NaN: the map lists it, or no bearing or route to place it by)."""
        b = track.bearing_rad
        if math.isfinite(track.line_m) or not math.isfinite(b) or view.path is None or abs(b) >= math.pi / 2:
            return math.nan
        x, y, yaw = (float(v) for v in view.pose)
        cx, cy = self._camera_xy
        cam_x, cam_y = x + cx * math.cos(yaw) - cy * math.sin(yaw), y + cx * math.sin(yaw) + cy * math.cos(yaw)
        ray = max(depth_m, 0.0) / math.cos(b)  # the depth is along the camera's axis, the target off it by b
        # Along the route the target lies between its straight-line distance and half a circle's arc of it.
        s, _ = view.path.project(np.array([cam_x + ray * math.cos(yaw + b), cam_y + ray * math.sin(yaw + b)]),
                                 s_hint=view.progress_m + ray, window_m=ray + 1.0)
        return float(s) - (track.stop_at_m - self._bumper_m)  # stop_at_m: the camera's depth at the line

    def _room_unlisted(self, view: CarView, track: TargetTrack) -> float:
        """The room to an unlisted target's line: along the route from the car's bumper to where the car
        placed the line, else along the camera's axis (the near end less the line's camera depth)."""
        if not math.isfinite(self.line_s) or view.path is None:
            return self.near_m - track.stop_at_m
        x, y, yaw = (float(v) for v in view.pose)
        ahead = self._camera_xy[0] + self._bumper_m
        s, _ = view.path.project(np.array([x + ahead * math.cos(yaw), y + ahead * math.sin(yaw)]),
                                 s_hint=view.progress_m)
        return self.line_s - float(s)

    def _vouch(self, track: TargetTrack) -> float:
        """This step's vouched distance to the target (NaN: none)."""
        ranges = [r for r in track.ranges if math.isfinite(r) and r > 0]
        if self.held:  # a range reading where the carried target is: the same target
            near = [r for r in ranges if self.near_m - agree_m(r) <= r <= self.far_m + agree_m(r)]
            if near:
                return min(near)
        witnesses = sorted(r for r in (*track.ranges, track.size_m, track.map_m) if math.isfinite(r) and r > 0)
        agreeing = [(a, b) for a, b in zip(witnesses, witnesses[1:]) if b - a <= agree_m(a)]
        # The map alone with the size (no range witness) or an unlisted target first seen: two range witnesses.
        unlisted = not math.isfinite(track.map_m) and not self.seen
        if unlisted:
            agreeing = [(a, b) for a, b in agreeing if a in ranges and b in ranges]
        else:
            agreeing = [(a, b) for a, b in agreeing if a in ranges or b in ranges]
        self.agreed = self.agreed + 1 if agreeing else 0
        if self.agreed < CONFIRM_FRAMES and not self.held:
            return math.nan
        return min(a for a, _ in agreeing) if agreeing else math.nan

    def _said(self, cap: float, vouched: bool, outvoted: bool, stop: bool) -> StageLimit:
        p = self._prefix
        return StageLimit(cap, {f"{p}vouched": vouched, f"{p}carried": self.held and not self.done,
                                f"{p}near": self.near_m if self.held and not self.done else math.nan,
                                f"{p}outvoted": outvoted, f"{p}stop": stop, f"{p}cap": cap})

    def idle(self) -> StageLimit:
        return self._said(math.inf, False, False, False)


@lru_cache(maxsize=None)
def static_supervisor(kind: str) -> type[StaticSupervisor]:
    """The static supervisor of ``kind``'s track, with its own columns (``sup_KIND_*``)."""
    return type(f"StaticSupervisor_{kind}", (StaticSupervisor,),
                {"supervises": kind, "name": f"supervisor_{kind}", "columns": _columns(kind), "__module__": __name__})


StaticSupervisor.columns = _columns("sign")
