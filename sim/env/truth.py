"""The referee's truth about the target, read from the world: where each target's body stands against
where the map puts it (``racf.sim.env.ground_truth.Motion``, from MuJoCo's body poses), so that the
truth follows a sign or a crate a world manager moved, turned or took away; and the target's mask in
the held camera frame (projected where the frame saw the body, against the frame's clean depth: no
second render)."""

from __future__ import annotations

import numpy as np

from racf.sim._gl import ensure_gl_backend
from racf.sim.env.ground_truth import Motion, SignView, obstacle_view, sign_view, target_centre, with_centre_from
from racf.sim.sensors.camera import CameraIntrinsics
from racf.sim.world.obstacles import Obstacle, obstacles
from racf.sim.world.scene import obstacle_body, sign_body
from racf.sim.world.stop_signs import SignGeometry, StopSign, stop_signs

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["TargetBodies", "WorldTruth"]


class TargetBodies:
    """Every target's body and its map pose (the MJCF's, before any manager acted), and the bodies'
    poses when the held camera frame was taken."""

    def __init__(self, model: mujoco.MjModel, sign_geometry: SignGeometry) -> None:
        self._bodies = {**{("stop_sign", s.index): model.body(sign_body(s.index)).id for s in stop_signs(sign_geometry)},
                        **{("obstacle", o.index): model.body(obstacle_body(o.index)).id for o in obstacles()}}
        home = mujoco.MjData(model)
        mujoco.mj_kinematics(model, home)
        self._home = {key: (home.xpos[body].copy(), home.xmat[body].copy()) for key, body in self._bodies.items()}
        self._frame_xpos, self._frame_xmat = home.xpos.copy(), home.xmat.copy()

    def hold_frame(self, data: mujoco.MjData) -> None:
        """Keeps the bodies' poses of the camera frame just taken."""
        self._frame_xpos[:], self._frame_xmat[:] = data.xpos, data.xmat

    def motion(self, target: StopSign | Obstacle, data: mujoco.MjData | None = None) -> Motion | None:
        """How ``target``'s body stands off its map pose in ``data`` now (None: the held frame's poses);
        None when it stands exactly where the map puts it."""
        key = ("obstacle" if isinstance(target, Obstacle) else "stop_sign", target.index)
        body = self._bodies[key]
        xpos, xmat = (self._frame_xpos, self._frame_xmat) if data is None else (data.xpos, data.xmat)
        return Motion.between(*self._home[key], xpos[body], xmat[body])


class WorldTruth:
    """The held camera frame's truth (its clean depth, the camera's and the bodies' poses) and the
    target's view from it, computed once per frame and target."""

    def __init__(self, model: mujoco.MjModel, sign_geometry: SignGeometry, intrinsics: CameraIntrinsics) -> None:
        self.bodies = TargetBodies(model, sign_geometry)
        self.intrinsics = intrinsics
        self._depth = np.zeros((intrinsics.height, intrinsics.width), np.float32)
        self._camera = (np.zeros(3), np.eye(3))
        self._view: tuple[tuple[int, int], SignView] | None = None

    def hold_frame(self, data: mujoco.MjData, clean_depth: np.ndarray, cam_pos, cam_mat) -> None:
        """Keeps the frame just taken: its noise-free depth, the camera's pose and the bodies' poses."""
        self._depth[:] = clean_depth
        self._camera = (np.array(cam_pos, dtype=np.float64), np.array(cam_mat, dtype=np.float64).reshape(3, 3))
        self.bodies.hold_frame(data)

    @property
    def frame_camera(self) -> tuple[np.ndarray, np.ndarray]:
        """The held frame's camera pose: (position (3,), camera-to-world rotation (3, 3))."""
        return self._camera

    def frame_body(self, body: int) -> tuple[np.ndarray, np.ndarray]:
        """Where body ``body`` stood when the held frame was taken: (position (3,), rotation (9,))."""
        return self.bodies._frame_xpos[body].copy(), self.bodies._frame_xmat[body].copy()

    def forget_view(self) -> None:
        """The world changed under the held frame (a reset, a sticker put up): compute the view anew."""
        self._view = None

    def view(self, target: StopSign | Obstacle, key: tuple, data: mujoco.MjData, cam_pos, cam_mat
             ) -> tuple[SignView, np.ndarray]:
        """The target's view: its mask as the held frame shows it (computed once per ``key``: the frame and
        the target's slot), its depth and bearing from where the camera and the body are now; and where its
        centre stands now."""
        if self._view is None or self._view[0] != key:
            view_of = obstacle_view if isinstance(target, Obstacle) else sign_view
            self._view = (key, view_of(target, *self._camera, self.intrinsics, self._depth, self.bodies.motion(target)))
        centre = target_centre(target, self.bodies.motion(target, data))
        return with_centre_from(self._view[1], centre, np.asarray(cam_pos, np.float64),
                                np.asarray(cam_mat, np.float64).reshape(3, 3)), centre

    def sign_masks(self, signs) -> list[np.ndarray]:
        """Every stop sign's visible face in the held frame, (H, W) bool each."""
        return [sign_view(s, *self._camera, self.intrinsics, self._depth, self.bodies.motion(s)).mask for s in signs]
