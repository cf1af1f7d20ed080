"""The offscreen third-person view behind the car that ``QCar2Env.render()`` returns (nothing the
car senses: a view for people)."""

from __future__ import annotations

import numpy as np

from racf.sim._gl import ensure_gl_backend, gl_context_class

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["ChaseView"]


class ChaseView:
    """Offscreen third-person view behind the car (for ``render()``)."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int) -> None:
        self._gl = gl_context_class()(width, height)
        self._gl.make_current()
        self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100.value)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._con)
        self._scene = mujoco.MjvScene(model, maxgeom=2000)
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._cam.fixedcamid = model.camera("chase").id
        self._opt = mujoco.MjvOption()
        self._model = model
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._rgb = np.empty((height, width, 3), np.uint8)

    def upload_texture(self, texture_id: int) -> None:
        self._gl.make_current()
        mujoco.mjr_uploadTexture(self._model, self._con, texture_id)

    def render(self, data: mujoco.MjData) -> np.ndarray:
        self._gl.make_current()
        mujoco.mjv_updateScene(self._model, data, self._opt, None, self._cam, mujoco.mjtCatBit.mjCAT_ALL.value, self._scene)
        mujoco.mjr_render(self._rect, self._scene, self._con)
        mujoco.mjr_readPixels(self._rgb, None, self._rect, self._con)
        return self._rgb[::-1].copy()

    def close(self) -> None:
        self._con.free()
        self._gl.free()
