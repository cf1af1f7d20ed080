"""Rendered views for the learned stop-sign segmenter: frames with their ground-truth sign masks.

A view puts the car's camera somewhere on the map, sets the room's lighting, may move
distractors (the yield signs, traffic lights and crates) into the picture, renders the
camera's RGB frame and asks the ground truth which pixels show a stop sign's face.

- ``sign`` views look at one stop sign from 0.3-4 m, up to 60 deg off its face normal,
  with the sign anywhere across the image;
- ``map`` views stand anywhere on the mat, looking anywhere (mostly no stop sign:
  the negatives, with the map's red yield signs and lamps).

Everything a view is comes from its :class:`ViewSpec`, drawn from a seeded generator, so
the same seed renders the same frames.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from racf import sim
from racf.sim.env.ground_truth import face_area_px, sign_view
from racf.sim.world import map_facts
from racf.sim.world.stop_signs import stop_signs

__all__ = ["ViewSpec", "View", "ViewRenderer", "draw_view", "draw_distractors", "DISTRACTOR_BODIES", "SIGN_RANGE_M",
           "FAR_RANGE_M"]

#: Distance of a ``sign`` view's camera from the sign, m.
SIGN_RANGE_M = (0.3, 4.0)
#: Distance of a far ``sign`` view's camera from the sign, m: first sight on the longer run-ups,
#: where the sign is a few pixels across and a far red prop looks most like it.
FAR_RANGE_M = (4.0, 6.0)
#: Largest angle between a ``sign`` view's line of sight and the sign's face normal, rad.
MAX_OFF_NORMAL_RAD = math.radians(60.0)
#: The props a view may move into the picture (bodies of the map).
DISTRACTOR_BODIES = tuple([f"yield_sign_{i}" for i in range(len(map_facts.YIELD_SIGNS))]
                          + [f"traffic_light_{i}" for i in range(len(map_facts.TRAFFIC_LIGHTS))]
                          + ["obstacle_0", "obstacle_1"])
#: The room's lighting in the map as built: headlight ambient, headlight diffuse, ceiling diffuse.
DEFAULT_LIGHTING = (0.45, 0.35, 0.5)
_HALF_FOV_RAD = math.radians(30.0)


@dataclass(frozen=True)
class ViewSpec:
    """Where the camera is and what the room looks like for one frame.

    Attributes:
        kind: ``sign``, ``approach`` (a pose on the lane towards the sign) or ``map``.
        sign: the stop sign a ``sign`` or ``approach`` view looks at (-1 for ``map``).
        camera_xy: (x, y) of the camera in the map frame, m.
        yaw, pitch, roll: the car's attitude, rad.
        lighting: (headlight ambient, headlight diffuse, ceiling diffuse) intensities.
        tint: (3,) colour multipliers of the headlight (white balance).
        distractors: (body name, x, y, yaw) of props moved for this view.
    """

    kind: str
    sign: int
    camera_xy: tuple[float, float]
    yaw: float
    pitch: float
    roll: float
    lighting: tuple[float, float, float]
    tint: tuple[float, float, float]
    distractors: tuple[tuple[str, float, float, float], ...] = ()


@dataclass(frozen=True)
class View:
    """One rendered view.

    Attributes:
        spec: what was rendered.
        rgb: (H, W, 3) uint8 frame.
        mask: (H, W) bool, pixels of any stop sign's face (visible, facing the camera).
        sign_masks: per stop sign, its pixel count in ``mask``.
        target: (H, W) bool, the viewed sign's face (``sign`` views; all False otherwise).
        target_share: the share of the viewed sign's whole face that ``target`` shows (props and
            the frame's edges hide the rest); 0 for ``map`` views.
        faces_share: the same for every stop sign with a pixel in ``mask`` (1 when none has).
        cam_pos, cam_mat: the camera's position (3,) and camera-to-world rotation (3, 3).
        d_true: depth of the viewed sign's centre (``sign`` views), m; NaN otherwise.
    """

    spec: ViewSpec
    rgb: np.ndarray
    mask: np.ndarray
    sign_masks: tuple[int, ...]
    target: np.ndarray
    target_share: float
    faces_share: float
    cam_pos: np.ndarray
    cam_mat: np.ndarray
    d_true: float


def draw_view(rng: np.random.Generator, kind: str, distractor_p: float = 0.5,
              range_m: tuple[float, float] = SIGN_RANGE_M) -> ViewSpec:
    """A random view of ``kind`` (``sign`` or ``map``) from ``rng``; a ``sign`` view's camera
    stands ``range_m`` from the sign."""
    if kind not in ("sign", "map"):
        raise ValueError(f"kind must be 'sign' or 'map', got {kind!r}")
    signs = stop_signs()
    pitch, roll = (float(v) for v in rng.normal(0.0, math.radians(1.5), 2))
    lighting = (float(rng.uniform(0.25, 0.6)), float(rng.uniform(0.15, 0.5)), float(rng.uniform(0.2, 0.8)))
    tint = tuple(float(v) for v in rng.uniform(0.9, 1.1, 3))
    if kind == "sign":
        index = int(rng.integers(len(signs)))
        sign = signs[index]
        d = float(rng.uniform(*range_m))
        off = float(rng.uniform(-MAX_OFF_NORMAL_RAD, MAX_OFF_NORMAL_RAD))
        direction = sign.face_yaw + off
        xy = (sign.position[0] + d * math.cos(direction), sign.position[1] + d * math.sin(direction))
        # Look back at the sign, with the sign anywhere across the image.
        yaw = direction + math.pi + float(rng.uniform(-0.85, 0.85)) * _HALF_FOV_RAD
    else:
        index = -1
        x0, x1, y0, y1 = map_facts.WALL_BOUNDS_M
        xy = (float(rng.uniform(x0 + 0.2, x1 - 0.2)), float(rng.uniform(y0 + 0.2, y1 - 0.2)))
        yaw = float(rng.uniform(-math.pi, math.pi))
    distractors = draw_distractors(rng, xy, yaw) if rng.random() < distractor_p else ()
    return ViewSpec(kind, index, (float(xy[0]), float(xy[1])), float(yaw), pitch, roll, lighting, tint,
                    distractors)


def draw_distractors(rng: np.random.Generator, camera_xy: tuple[float, float],
                     yaw: float) -> tuple[tuple[str, float, float, float], ...]:
    """One or two props (yield signs, traffic lights, crates) moved into the field of view of a
    camera at ``camera_xy`` looking along ``yaw``: (body name, x, y, yaw) each."""
    out = []
    for name in rng.choice(DISTRACTOR_BODIES, size=int(rng.integers(1, 3)), replace=False):
        r = float(rng.uniform(0.35, 2.5))
        a = yaw + float(rng.uniform(-1.0, 1.0)) * _HALF_FOV_RAD
        out.append((str(name), camera_xy[0] + r * math.cos(a), camera_xy[1] + r * math.sin(a),
                    float(rng.uniform(-math.pi, math.pi))))
    return tuple(out)


class ViewRenderer:
    """Renders :class:`ViewSpec` s with the env's own camera (its model, intrinsics and renderer).

    Args:
        env_kwargs: settings of the env whose camera renders (default: the env's defaults).
    """

    def __init__(self, **env_kwargs) -> None:
        import mujoco

        self._mujoco = mujoco
        self.env = gym.make(sim.ENV_ID, **env_kwargs)
        self.env.reset(seed=0, options={"sign": 0})
        u = self.env.unwrapped
        self.model, self.data, self.rig, self.car = u.model, u.data, u.rig, u.car
        self.signs = u.signs if hasattr(u, "signs") else stop_signs(u.config.sign)
        self._home = {name: (self.model.body(name).pos.copy(), self.model.body(name).quat.copy())
                      for name in DISTRACTOR_BODIES}
        # The camera's offset from the car's root, in the car's frame (a fixed mount).
        self.car.place(self.data, 0.0, 0.0, 0.0)
        mujoco.mj_forward(self.model, self.data)
        self._cam_offset = self.car.camera_pose(self.model, self.data)[0][:2].copy()
        self._light = self.model.light("ceiling").id

    @property
    def intrinsics(self):
        return self.rig.intrinsics

    @property
    def camera_offset(self) -> tuple[float, float]:
        """The camera ahead of and left of the car's root, m (its fixed mount)."""
        return float(self._cam_offset[0]), float(self._cam_offset[1])

    def render(self, spec: ViewSpec) -> View:
        """The frame and ground truth of ``spec``."""
        m, d, mj = self.model, self.data, self._mujoco
        for name, (pos, quat) in self._home.items():
            m.body(name).pos[:] = pos
            m.body(name).quat[:] = quat
        for name, x, y, yaw in spec.distractors:
            m.body(name).pos[:2] = (x, y)
            m.body(name).quat[:] = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        ambient, diffuse, ceiling = spec.lighting
        m.vis.headlight.ambient[:] = ambient * np.asarray(spec.tint)
        m.vis.headlight.diffuse[:] = diffuse * np.asarray(spec.tint)
        m.light_diffuse[self._light] = ceiling
        c, s = math.cos(spec.yaw), math.sin(spec.yaw)
        ox, oy = self._cam_offset
        x, y = spec.camera_xy[0] - (c * ox - s * oy), spec.camera_xy[1] - (s * ox + c * oy)
        q = self.car.root_qpos
        d.qpos[q:q + 3] = (x, y, 0.0)
        d.qpos[q + 3:q + 7] = _quat_zyx(spec.yaw, spec.pitch, spec.roll)
        mj.mj_forward(m, d)
        self.rig.invalidate()
        rgb, depth = self.rig.render(m, d)
        self.last_depth = depth.copy()  # the frame's depth (the vehicle views' masks compare two)
        cam_pos, cam_mat = self.car.camera_pose(m, d)
        mask = np.zeros(rgb.shape[:2], bool)
        target = np.zeros(rgb.shape[:2], bool)
        counts, d_true, share, seen_px, seen_area = [], float("nan"), 0.0, 0, 0.0
        for sign in self.signs:
            sv = sign_view(sign, cam_pos, cam_mat, self.rig.intrinsics, depth)
            mask |= sv.mask
            px = int(sv.mask.sum())
            counts.append(px)
            area = face_area_px(sign, cam_pos, cam_mat, self.rig.intrinsics) if px else 0.0
            seen_px, seen_area = seen_px + px, seen_area + area
            if sign.index == spec.sign:
                target, d_true = sv.mask, sv.d_true
                share = min(1.0, px / area) if area > 0 else 0.0
        faces_share = min(1.0, seen_px / seen_area) if seen_area > 0 else 1.0
        return View(spec, rgb.copy(), mask, tuple(counts), target, share, faces_share, cam_pos, cam_mat, d_true)

    def restore(self) -> None:
        """Puts the props and the lighting back as the map has them."""
        for name, (pos, quat) in self._home.items():
            self.model.body(name).pos[:] = pos
            self.model.body(name).quat[:] = quat
        ambient, diffuse, ceiling = DEFAULT_LIGHTING
        self.model.vis.headlight.ambient[:] = ambient
        self.model.vis.headlight.diffuse[:] = diffuse
        self.model.light_diffuse[self._light] = ceiling
        self.rig.invalidate()

    def close(self) -> None:
        self.env.close()


def _quat_zyx(yaw: float, pitch: float, roll: float) -> tuple[float, float, float, float]:
    """(w, x, y, z) of the rotation yaw about z, then pitch about y, then roll about x."""
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)
