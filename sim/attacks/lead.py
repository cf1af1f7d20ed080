"""Attacks on a vehicle ahead (``acts_on = "vehicle"``: the first vehicle a scenario's world declares,
``WorldManager.targets()``; the ``lead_vehicle`` scenario's lead, or a user's own car), each on the
sensors as the literature poses it, from the attacker's ground truth of where that vehicle stands:

- ``lead_patch``: the paper's patch injection on the depth inside the lead's box, reading it
  ``bias_m`` far (the depth-estimation patch on a car's rear: Cheng et al., ECCV 2022);
- ``lead_ramp``: the same bias grown at ``rate_mps`` (stealthy: each frame near the last);
- ``lead_frustum``: the LiDAR's returns from the lead moved ``bias_m`` away along their beams
  (LiDAR spoofing and the frustum attack: Cao et al., CCS 2019; Hallyburton et al., USENIX
  Security 2022); with ``depth`` the camera's depth moves with them, so the two agree; with
  ``scale_box`` the camera's picture of the lead too, drawn as small as it would look there, and
  with ``rate_mps`` the move grows at that rate (the adaptive attack on ODCA: every witness, the
  size and the relative motion included, tells the same story of a lead that drives away);
- ``lead_hide``: the lead hidden from camera and LiDAR together, what MSF-ADV's object achieves
  (Cao et al., S&P 2021): its pixels painted over from their surroundings, no depth return
  there and no LiDAR return from it;
- ``lead_range_error``: an error within a bound on every range witness of the lead together (its
  depth and its LiDAR returns moved by ``bias_m + amp_m sin(2 pi t / period_s + phase_rad)``): what the
  supervisor's guarantee assumes a vouched distance may be off by (its falsification's error injection);
- ``lead_phantom``: a phantom car ahead (Nassi et al., CCS 2020: a car's picture projected or
  shown where none stands): the camera sees a QCar 2's rear ``distance_m`` ahead in the lane,
  while the depth and the LiDAR see what is really there (a picture has no depth).

They act from ``start_s`` (``trigger="at_time"``: before the lead brakes, by default) for the
episode's ``t_atk``. The lead's pixels are its declared box (``WorldTarget.size_m``; a QCar 2's,
0.425 x 0.192 x 0.2 m) projected into the frame, where the depth is no farther than the box's far side.
"""

from __future__ import annotations

import math
from typing import Any

import cv2
import gymnasium as gym
import numpy as np

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.image_scale import scale_region
from racf.sim.attacks.schedule import AttackSchedule, as_range
from racf.sim.world.manager import WorldTarget, world_targets

__all__ = ["LeadPatch", "LeadRamp", "LeadFrustum", "LeadHide", "LeadPhantom", "LeadRangeError", "lead_pixels",
           "lead_beams", "attacked_vehicle"]
_MJ_TO_OPTICAL = np.diag([1.0, -1.0, -1.0])
#: Where a lead attack starts by default, s into the episode (the scenario's lead brakes at 3 s).
DEFAULT_START_S = 2.0


def attacked_vehicle(env: gym.Env) -> WorldTarget | None:
    """The vehicle these attacks aim at: the first one the env's world declares (None: none)."""
    found = world_targets(getattr(env.unwrapped, "world", ()), "vehicle")
    return found[0] if found else None


def _corners(lead: tuple[float, float, float], size_m: tuple[float, float, float]) -> np.ndarray:
    x, y, yaw = lead
    length, width, height = size_m
    c, s = math.cos(yaw), math.sin(yaw)
    out = []
    for a in (-0.5, 0.5):
        for b in (-0.5, 0.5):
            px, py = x + c * a * length - s * b * width, y + s * a * length + c * b * width
            out += [(px, py, 0.0), (px, py, height)]
    return np.array(out)


def lead_pixels(env: gym.Env, info: dict, depth: np.ndarray) -> np.ndarray:
    """(H, W) bool: the lead's pixels in the frame (ground truth: the attacker's knowledge), its box
    projected from where the camera and the lead stood when the frame was taken."""
    u = env.unwrapped
    mask = np.zeros(depth.shape, bool)
    target = attacked_vehicle(env)
    if target is None or target.pose(info) is None:
        return mask
    cam_pos, cam_mat = u.truth.frame_camera
    xpos, xmat = u.truth.frame_body(u.model.body(target.body).id)
    lead = (float(xpos[0]), float(xpos[1]), math.atan2(float(xmat[3]), float(xmat[0])))
    k = u.truth.intrinsics
    pts = (_MJ_TO_OPTICAL @ np.asarray(cam_mat).reshape(3, 3).T @ (_corners(lead, target.size_m) - cam_pos).T).T
    if np.all(pts[:, 2] <= 0.05):
        return mask
    pts = pts[pts[:, 2] > 0.05]
    uv = np.column_stack([k.cx + k.fx * pts[:, 0] / pts[:, 2], k.cy + k.fy * pts[:, 1] / pts[:, 2]])
    hull = cv2.convexHull(np.clip(uv, -1e4, 1e4).astype(np.int32))
    poly = np.zeros(depth.shape, np.uint8)
    cv2.fillConvexPoly(poly, hull, 1)
    poly = cv2.dilate(poly, np.ones((3, 3), np.uint8))  # the box's edges fall between pixels
    return poly.astype(bool) & (depth > 0) & (depth <= float(pts[:, 2].max()) + 0.05)


def lead_beams(env: gym.Env, info: dict, scan: np.ndarray) -> np.ndarray:
    """(N,) bool: the LiDAR beams whose return is the lead's."""
    u = env.unwrapped
    beams = np.zeros(len(scan), bool)
    target = attacked_vehicle(env)
    lead = None if target is None else target.pose(info)
    if lead is None:
        return beams
    lidar = u.data.site("lidar")
    yaw = float(np.arctan2(lidar.xmat[3], lidar.xmat[0]))
    corners = _corners(lead, target.size_m)[::2, :2] - lidar.xpos[:2]
    bearings = np.arctan2(corners[:, 1], corners[:, 0]) - yaw
    centre = math.atan2(lead[1] - lidar.xpos[1], lead[0] - lidar.xpos[0]) - yaw
    rel = (bearings - centre + np.pi) % (2 * np.pi) - np.pi
    angles = 2 * np.pi * np.arange(len(scan)) / len(scan)
    diff = (angles - centre + np.pi) % (2 * np.pi) - np.pi
    far = float(np.linalg.norm(corners, axis=1).max())
    return (diff >= rel.min() - 0.01) & (diff <= rel.max() + 0.01) & np.isfinite(scan) & (scan > 0) & (scan <= far + 0.05)


class _LeadAttack(AttackWrapper):
    """A lead attack: on the ``at_time`` schedule from ``start_s`` unless told otherwise.

    One that names a ``drawn`` parameter, (name, lowest, highest), takes it as a value or a (low,
    high) range and draws it once an episode into ``self.drawn_value``."""

    targets = ("sign",)
    acts_on = "vehicle"
    drawn: tuple[str, float, float] | None = None

    def __init__(self, env: gym.Env, drawn_value: Any = None, **schedule: Any) -> None:
        if self.drawn is not None:
            name, lo, hi = self.drawn
            self.drawn_range = as_range(name, drawn_value, lo, hi)
            self.drawn_value = self.drawn_range[0]
        schedule = {"trigger": "at_time", "start_s": DEFAULT_START_S, **schedule}
        super().__init__(env, AttackSchedule(**schedule))

    def _on_reset(self) -> None:
        if self.drawn is not None:
            self.drawn_value = float(self.rng.uniform(*self.drawn_range))

    def _shift_depth(self, obs: dict, info: dict, bias: float) -> dict:
        depth = obs["depth"].copy()
        plane = depth[..., 0]
        where = lead_pixels(self, info, plane)
        plane[where] = np.maximum(plane[where] + bias, 0.0).astype(depth.dtype)
        obs["depth"] = depth
        return obs


class LeadPatch(_LeadAttack):
    """The lead's depth read ``bias_m`` far inside its box (a value or a (low, high) range per episode)."""

    name = "lead_patch"
    drawn = ("bias_m", 0.0, 10.0)

    def __init__(self, env: gym.Env, bias_m: Any = 1.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, bias_m=bias_m, **schedule)
        super().__init__(env, bias_m, **schedule)

    def _attack(self, obs: dict, info: dict) -> dict:
        return self._shift_depth(obs, info, self.drawn_value)


class LeadRamp(_LeadAttack):
    """The lead's depth read far by a bias growing at ``rate_mps`` up to ``max_m`` (stealthy)."""

    name = "lead_ramp"

    def __init__(self, env: gym.Env, rate_mps: float = 0.5, max_m: float = 2.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, rate_mps=rate_mps, max_m=max_m, **schedule)
        if not (0.0 < rate_mps <= 10.0 and 0.0 < max_m <= 10.0):
            raise ValueError(f"rate_mps must be in (0, 10] m/s and max_m in (0, 10] m, got {rate_mps!r}, {max_m!r}")
        self.rate_mps, self.max_m = float(rate_mps), float(max_m)
        super().__init__(env, **schedule)

    def _attack(self, obs: dict, info: dict) -> dict:
        start = self.schedule.windows[-1][0]
        return self._shift_depth(obs, info, min(self.rate_mps * (float(info["time"]) - start), self.max_m))


class LeadFrustum(_LeadAttack):
    """The LiDAR's returns from the lead moved ``bias_m`` away along their beams; with ``depth`` the
    camera's depth of the lead moves with them (the frustum attack: the two agree).

    With ``scale_box`` the colour image's lead (and, with ``depth``, its depth) is redrawn as the
    same car moved along the camera's rays to its spoofed distance: scaled by d / (d + bias) about
    the principal point, its old pixels filled from around them, so the size witness agrees too.
    With ``rate_mps`` > 0 the move grows at that rate from the attack's start up to ``bias_m``, as
    a lead pulling away would, instead of jumping there: the relative motion agrees as well.
    """

    name = "lead_frustum"
    drawn = ("bias_m", 0.0, 10.0)

    def __init__(self, env: gym.Env, bias_m: Any = 1.0, depth: bool = False, scale_box: bool = False,
                 rate_mps: float = 0.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, bias_m=bias_m, depth=depth, scale_box=scale_box,
                                                 rate_mps=rate_mps, **schedule)
        for flag, value in (("depth", depth), ("scale_box", scale_box)):
            if not isinstance(value, bool):
                raise ValueError(f"{flag} must be true or false, got {value!r}")
        if not (isinstance(rate_mps, (int, float)) and 0.0 <= rate_mps <= 10.0):
            raise ValueError(f"rate_mps must be in [0, 10] m/s (0: the whole move at once), got {rate_mps!r}")
        self.with_depth, self.scale_box, self.rate_mps = depth, scale_box, float(rate_mps)
        super().__init__(env, bias_m, **schedule)

    def bias(self, info: dict) -> float:
        """The move now, m: all of ``bias_m`` at once, or grown at ``rate_mps`` since the attack began."""
        if self.rate_mps == 0.0:
            return self.drawn_value
        return min(self.rate_mps * (float(info["time"]) - self.schedule.windows[-1][0]), self.drawn_value)

    def _attack(self, obs: dict, info: dict) -> dict:
        bias = self.bias(info)
        scan = np.asarray(obs["lidar"]).copy()
        beams = lead_beams(self, info, scan)
        scan[beams] += bias
        obs["lidar"] = scan.astype(obs["lidar"].dtype)
        if not self.scale_box:
            return self._shift_depth(obs, info, bias) if self.with_depth else obs
        return self._redraw_farther(obs, info, bias)

    def _redraw_farther(self, obs: dict, info: dict, bias: float) -> dict:
        plane = np.asarray(obs["depth"])[..., 0]
        where = lead_pixels(self, info, plane)
        if where.sum() < 4 or bias <= 0.0:
            return self._shift_depth(obs, info, bias) if self.with_depth else obs
        d = float(np.median(plane[where]))
        k = self.unwrapped.truth.intrinsics
        factor, centre = d / (d + bias), (k.cx, k.cy)
        obs["rgb"] = scale_region(np.ascontiguousarray(obs["rgb"]), where, factor, centre)
        if self.with_depth:
            moved = np.where(where, plane + bias, plane).astype(np.float32)
            shifted = scale_region(moved, where, factor, centre)
            depth = obs["depth"].copy()
            depth[..., 0] = shifted.astype(depth.dtype)
            obs["depth"] = depth
        return obs


class LeadHide(_LeadAttack):
    """The lead gone from every sensor: its pixels inpainted from their surroundings (OpenCV's Telea),
    its depth no return, and the LiDAR's returns from it no return."""

    name = "lead_hide"

    def __init__(self, env: gym.Env, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, **schedule)
        super().__init__(env, **schedule)

    def _attack(self, obs: dict, info: dict) -> dict:
        depth = obs["depth"].copy()
        plane = depth[..., 0]
        where = lead_pixels(self, info, plane)
        rgb = cv2.inpaint(np.ascontiguousarray(obs["rgb"]), cv2.dilate(where.astype(np.uint8), np.ones((5, 5), np.uint8)), 5,
                          cv2.INPAINT_TELEA)
        plane[where] = 0.0
        scan = np.asarray(obs["lidar"]).copy()
        scan[lead_beams(self, info, scan)] = np.inf
        obs.update(rgb=rgb, depth=depth, lidar=scan.astype(obs["lidar"].dtype))
        return obs


class LeadPhantom(_LeadAttack):
    """A phantom car ``distance_m`` ahead of the camera: the colour image only.

    The attacker's picture is a QCar 2's rear as the camera sees the real one, drawn as it would
    look at ``distance_m`` (a value or a (low, high) range per episode) at the same bearing and
    height: the lead's pixels scaled by (its depth / ``distance_m``) about the principal point,
    which is where every point of a car moved along its rays to that depth projects. The depth
    and the LiDAR are left as they are: what a picture on the road, a projector's or a screen's,
    gives the range sensors is the road (Nassi et al., CCS 2020). While the lead is out of the
    frame there is no picture to draw from, and the frame is left alone.
    """

    name = "lead_phantom"
    drawn = ("distance_m", 0.2, 5.0)

    def __init__(self, env: gym.Env, distance_m: Any = 0.5, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, distance_m=distance_m, **schedule)
        super().__init__(env, distance_m, **schedule)

    def _attack(self, obs: dict, info: dict) -> dict:
        plane = np.asarray(obs["depth"])[..., 0]
        where = lead_pixels(self, info, plane)
        if where.sum() < 4:
            return obs
        scale = float(np.median(plane[where])) / self.drawn_value
        if scale <= 1.0:
            return obs  # the lead stands nearer than the phantom would: a picture behind it is hidden by it
        k = self.unwrapped.truth.intrinsics
        # Scaling about the principal point: the image of the same car moved along its rays.
        warp = np.array([[scale, 0.0, k.cx * (1 - scale)], [0.0, scale, k.cy * (1 - scale)]])
        rgb = np.ascontiguousarray(obs["rgb"])
        size = (rgb.shape[1], rgb.shape[0])
        picture = cv2.warpAffine(rgb, warp, size, flags=cv2.INTER_LINEAR)
        shown = cv2.warpAffine(where.astype(np.uint8), warp, size, flags=cv2.INTER_NEAREST).astype(bool)
        out = rgb.copy()
        out[shown] = picture[shown]
        obs["rgb"] = out
        return obs


class LeadRangeError(_LeadAttack):
    """Every range witness of the lead off by the same bounded error: its depth pixels and its LiDAR
    returns moved by ``bias_m + amp_m sin(2 pi t / period_s + phase_rad)`` (t from the attack's start;
    positive: farther). Its bound, ``|bias_m| + amp_m``, is the error the supervisor's guarantee
    assumes of a vouched distance (``Envelope.delta_m``): the falsification of that guarantee draws it
    within and beyond (``racf falsify --space guarantee.toml``)."""

    name = "lead_range_error"

    def __init__(self, env: gym.Env, bias_m: float = 0.05, amp_m: float = 0.05, period_s: float = 2.0,
                 phase_rad: float = 0.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, bias_m=bias_m, amp_m=amp_m, period_s=period_s,
                                                 phase_rad=phase_rad, **schedule)
        for name, value, lo, hi in (("bias_m", bias_m, -2.0, 2.0), ("amp_m", amp_m, 0.0, 2.0),
                                    ("period_s", period_s, 0.05, 60.0), ("phase_rad", phase_rad, -7.0, 7.0)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
                raise ValueError(f"{name} must be a number in [{lo}, {hi}], got {value!r}")
        self.bias_m, self.amp_m, self.period_s, self.phase_rad = float(bias_m), float(amp_m), float(period_s), float(phase_rad)
        super().__init__(env, **schedule)

    def error(self, info: dict) -> float:
        """The error now, m."""
        t = float(info["time"]) - self.schedule.windows[-1][0]
        return self.bias_m + self.amp_m * math.sin(2 * math.pi * t / self.period_s + self.phase_rad)

    def _attack(self, obs: dict, info: dict) -> dict:
        error = self.error(info)
        scan = np.asarray(obs["lidar"]).copy()
        scan[lead_beams(self, info, scan)] += error
        obs["lidar"] = scan.astype(obs["lidar"].dtype)
        return self._shift_depth(obs, info, error)
