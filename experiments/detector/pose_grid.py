"""The detectors' recall over the poses real signs stand in: a sign turned about its pole and leaned
back, seen from the car's lane at the approach distances (the detection literature's habit of
reporting recall over a pose range: GTSRB, the RP2 paper's angle sweeps).

Every view is a camera on the lane's centre line towards one of the four stop signs, at a
distance along the lane, with the room's light as the map has it; the sign's body is turned and
leaned in the scene, and the referee's truth (its mask and depth) follows the body. A view counts
where the target is resolvable (``evaluate.resolvable``); a hit is a detection overlapping it
(``evaluate.score_frame``). Nothing is drawn at random: the grid is the same on every machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.stats import wilson_interval

__all__ = ["TURNS_DEG", "LEANS_DEG", "DISTANCES_M", "GRID", "PoseView", "pose_views", "pose_recall"]

#: The grid: turns about the pole, leans back (degrees), and the camera's distance to the sign's foot
#: along the lane (m, first sight to the stop line: ``approach_views.APPROACH_RANGE_M``).
TURNS_DEG = (0.0, 15.0, 30.0, 45.0, 60.0)
LEANS_DEG = (0.0, 10.0, 20.0, 30.0)
DISTANCES_M = (0.6, 1.0, 1.5, 2.5, 3.5)
GRID = f"turn {', '.join(f'{t:g}' for t in TURNS_DEG)} deg x lean {', '.join(f'{v:g}' for v in LEANS_DEG)} deg x " \
       f"{', '.join(f'{d:g}' for d in DISTANCES_M)} m along the lane, the four stop signs"


@dataclass(frozen=True)
class PoseView:
    """One rendered view of a posed sign: the frame, the target's mask and the share of its face shown."""

    sign: int
    turn_deg: float
    lean_deg: float
    distance_m: float
    rgb: np.ndarray
    target: np.ndarray
    share: float


def _axis_quat(axis, angle_rad: float) -> np.ndarray:
    return np.array([math.cos(angle_rad / 2), *(math.sin(angle_rad / 2) * np.asarray(axis, float))])


def pose_views(turns=TURNS_DEG, leans=LEANS_DEG, distances=DISTANCES_M, signs=(0, 1, 2, 3)):
    """Yields a :class:`PoseView` for every sign, distance, turn and lean of the grid."""
    import mujoco

    from racf.experiments.detector.views import DEFAULT_LIGHTING, ViewRenderer, ViewSpec
    from racf.sim.env.ground_truth import Motion, face_area_px, sign_view
    from racf.sim.world.scene import sign_body

    renderer = ViewRenderer()
    m, d = renderer.model, renderer.data
    ox, oy = renderer.camera_offset
    try:
        for index in signs:
            sign = next(s for s in renderer.signs if s.index == index)
            body = m.body(sign_body(index)).id
            home_quat = m.body_quat[body].copy()
            mujoco.mj_forward(m, d)
            home = (d.xpos[body].copy(), d.xmat[body].copy())
            s_sign, _ = sign.path.project(np.asarray(sign.position), s_hint=sign.stop_s, window_m=0.6)
            for distance in distances:
                x, y, heading = sign.path.pose_at(s_sign - distance - ox)
                c, s = math.cos(heading), math.sin(heading)
                spec = ViewSpec("approach", index, (x + c * ox - s * oy, y + s * ox + c * oy), heading, 0.0, 0.0,
                                DEFAULT_LIGHTING, (1.0, 1.0, 1.0))
                for turn in turns:
                    for lean in leans:
                        turned = np.zeros(4)
                        mujoco.mju_mulQuat(turned, home_quat, _axis_quat((0, 0, 1), math.radians(turn)))
                        mujoco.mju_mulQuat(m.body_quat[body], turned, _axis_quat((0, 1, 0), -math.radians(lean)))
                        view = renderer.render(spec)  # runs mj_forward with the body turned
                        motion = Motion.between(*home, d.xpos[body], d.xmat[body])
                        truth = sign_view(sign, view.cam_pos, view.cam_mat, renderer.intrinsics, renderer.last_depth,
                                          motion)
                        area = face_area_px(sign, view.cam_pos, view.cam_mat, renderer.intrinsics, motion)
                        share = min(1.0, truth.mask.sum() / area) if area > 0 else 0.0
                        yield PoseView(index, turn, lean, distance, view.rgb, truth.mask, share)
            m.body_quat[body] = home_quat
    finally:
        renderer.restore()
        renderer.close()


def pose_recall(detectors: dict, views) -> dict:
    """Each detector's recall over ``views``, per turn and lean (pooled over distances and signs) and per
    distance: {"grid", "n_views", detector: {"overall", "by_pose": {"turn,lean": ...}, "by_distance": ...}},
    each rate with its Wilson interval and N (the resolvable views)."""
    from racf.experiments.detector.evaluate import score_frame

    counts: dict = {name: {} for name in detectors}
    n_views = 0
    for view in views:
        n_views += 1
        for name, detector in detectors.items():
            hit, _ = score_frame(detector.detect(view.rgb), view.target, view.target, view.share)
            if hit is None:
                continue
            for key in ("overall", f"pose {view.turn_deg:g},{view.lean_deg:g}", f"distance {view.distance_m:g}"):
                k, n = counts[name].get(key, (0, 0))
                counts[name][key] = (k + int(hit), n + 1)
    out: dict = {"grid": GRID, "n_views": n_views}
    for name, table in counts.items():
        rate = {key: _rate(*kn) for key, kn in table.items()}
        out[name] = {"overall": rate.get("overall"),
                     "by_pose": {k.split(" ", 1)[1]: v for k, v in rate.items() if k.startswith("pose ")},
                     "by_distance": {k.split(" ", 1)[1]: v for k, v in rate.items() if k.startswith("distance ")}}
    return out


def _rate(k: int, n: int) -> dict:
    return {"recall": k / n if n else None, "ci": list(wilson_interval(k, n)), "n": n}
