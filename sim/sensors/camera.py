"""Intel RealSense D435 RGB-D camera: colour and aligned depth from one render pass.

MuJoCo renders the colour and the depth buffer of the same frame; both are read back with
a single ``mjr_readPixels`` call. Depth is z-depth along the optical axis in metres (what a
RealSense reports), aligned to the colour image as RealSense's ``align`` does, with a
stereo-like noise model: error std ``k * z**2`` (k from the D435 baseline and sub-pixel
accuracy), 1 mm quantisation, 0 for no return (out of range or random dropout).

Intrinsics are the D435's colour intrinsics at 640x480 scaled to the chosen resolution.
The GL context is created lazily at the first read, so an env can be built in a parent
process and stepped in spawned workers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtri

from racf.sim._gl import ensure_gl_backend, gl_context_class
from racf.sim.sensors.base import Sensor

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["CameraConfig", "CameraIntrinsics", "RGBDCameraRig", "RGBCamera", "DepthCamera"]

_REF_W, _REF_H = 640, 480
_REF_FX, _REF_FY, _REF_CX, _REF_CY = 455.2, 459.4, 308.5, 213.6

#: Standard-normal draws for the depth noise by table lookup: a uniform 16-bit index picks one
#: of 2**16 equally likely quantiles (the midpoints of equal-probability bins). Three times
#: faster than numpy's ziggurat for a frame. The discretisation (steps under 0.004 sigma
#: within 3 sigma; tails cut at 4.3 sigma, which a frame of 76,800 pixels would pass about
#: once) is far below the 1 mm quantisation that follows.
_NORMAL_LEVELS = 2**16
_NORMAL_QUANTILES = ndtri((np.arange(_NORMAL_LEVELS) + 0.5) / _NORMAL_LEVELS).astype(np.float32)


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics in pixels; (u, v) = (cx + fx X/Z, cy + fy Y/Z), Y down."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def d435_colour(cls, width: int, height: int) -> "CameraIntrinsics":
        sx, sy = width / _REF_W, height / _REF_H
        return cls(width, height, _REF_FX * sx, _REF_FY * sy, _REF_CX * sx, _REF_CY * sy)

    def project(self, points_cam: np.ndarray) -> np.ndarray:
        """(N, 3) points in the optical frame (x right, y down, z forward) -> (N, 2) u, v."""
        z = points_cam[:, 2]
        return np.column_stack([self.cx + self.fx * points_cam[:, 0] / z,
                                self.cy + self.fy * points_cam[:, 1] / z])


@dataclass(frozen=True)
class CameraConfig:
    """RGB-D camera settings.

    Attributes:
        width, height: image size in pixels (4:3 keeps the D435's field of view).
        depth_min_m, depth_max_m: valid depth range; outside it depth is 0.
        depth_noise_k_per_m: std of the depth error is ``k * z**2`` (m); the D435's
            50 mm baseline with 0.08 px sub-pixel accuracy at ~430 px focal length gives
            about 0.0037 1/m.
        depth_dropout: probability that a valid pixel returns no depth.
        depth_quantum_m: depth resolution (the D435's z16 unit is 1 mm).
    """

    width: int = 320
    height: int = 240
    depth_min_m: float = 0.17
    depth_max_m: float = 10.0
    depth_noise_k_per_m: float = 0.0037
    depth_dropout: float = 0.005
    depth_quantum_m: float = 0.001

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            if isinstance(getattr(self, name), bool) or not isinstance(getattr(self, name), (int, np.integer)):
                raise ValueError(f"camera {name} must be an integer number of pixels, got {getattr(self, name)!r}")
        if not (16 <= self.width <= 1280 and 12 <= self.height <= 960):
            raise ValueError(f"camera width/height must be in [16, 1280] x [12, 960] px, got {self.width}x{self.height}")
        if not 0.0 < self.depth_min_m < self.depth_max_m <= 50.0:
            raise ValueError(f"need 0 < depth_min_m < depth_max_m <= 50 m, got {self.depth_min_m}, {self.depth_max_m}")
        if not 0.0 <= self.depth_noise_k_per_m <= 0.1:
            raise ValueError(f"depth_noise_k_per_m must be in [0, 0.1] 1/m, got {self.depth_noise_k_per_m}")
        if not 0.0 <= self.depth_dropout < 1.0:
            raise ValueError(f"depth_dropout must be in [0, 1), got {self.depth_dropout}")
        if not 0.0 <= self.depth_quantum_m <= 0.05:
            raise ValueError(f"depth_quantum_m must be in [0, 0.05] m, got {self.depth_quantum_m}")


class RGBDCameraRig:
    """Renders one camera of the model; caches the frame so RGB and depth share a pass.

    Args:
        config: image size and depth model.
        camera: name of the MJCF camera.
    """

    def __init__(self, config: CameraConfig, camera: str = "d435") -> None:
        self.config = config
        self.camera_name = camera
        self.intrinsics = CameraIntrinsics.d435_colour(config.width, config.height)
        self._gl = None
        self._con = None
        self._scene = None
        self._cam = None
        self._option = None
        self._frame_key: tuple | None = None
        self._rgb = np.empty((config.height, config.width, 3), np.uint8)
        self._zbuf = np.empty((config.height, config.width), np.float32)
        self._depth = np.empty((config.height, config.width), np.float32)

    def configure_model(self, model: mujoco.MjModel) -> None:
        """Writes this camera's intrinsics into the model (MuJoCo renders with them)."""
        cid = model.camera(self.camera_name).id
        k, pixel = self.intrinsics, 1e-5  # sensor pixel pitch: any value, only ratios matter
        model.cam_resolution[cid] = (k.width, k.height)
        model.cam_sensorsize[cid] = (k.width * pixel, k.height * pixel)
        # MuJoCo's principal point is the offset of the optical axis from the image centre,
        # in continuous coordinates (pixel i spans [i, i+1]); our cx, cy put pixel centres
        # on integers (OpenCV), hence the half pixel.
        model.cam_intrinsic[cid] = (k.fx * pixel, k.fy * pixel,
                                    (k.width / 2 - k.cx - 0.5) * pixel, (k.height / 2 - k.cy - 0.5) * pixel)

    def _ensure_context(self, model: mujoco.MjModel) -> None:
        if self._con is not None:
            return
        self._gl = gl_context_class()(self.config.width, self.config.height)
        self._gl.make_current()
        self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100.value)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._con)
        self._con.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._scene = mujoco.MjvScene(model, maxgeom=2000)
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._cam.fixedcamid = model.camera(self.camera_name).id
        self._option = mujoco.MjvOption()
        self._rect = mujoco.MjrRect(0, 0, self.config.width, self.config.height)
        extent = model.stat.extent
        near, far = np.float32(model.vis.map.znear * extent), np.float32(model.vis.map.zfar * extent)
        # Reversed-Z perspective: metric depth = d_coef / (zbuf + c_coef).
        c_coef = -(far + near) / (far - near)
        d_coef = -(np.float32(2) * far * near) / (far - near)
        self._c_coef = np.float32(-0.5) * c_coef - np.float32(0.5)
        self._d_coef = np.float32(-0.5) * d_coef

    def render(self, model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """(rgb (H, W, 3) uint8, noise-free z-depth (H, W) float32 m) of the current state.

        Rendered once per simulation state; repeated calls return the cached frame.
        """
        key = (id(data), data.time, data.qpos.tobytes())
        if key == self._frame_key:
            return self._rgb, self._depth
        self._ensure_context(model)
        self._gl.make_current()
        mujoco.mjv_updateScene(model, data, self._option, None, self._cam,
                               mujoco.mjtCatBit.mjCAT_ALL.value, self._scene)
        mujoco.mjr_render(self._rect, self._scene, self._con)
        mujoco.mjr_readPixels(self._rgb, self._zbuf, self._rect, self._con)
        # GL's origin is the bottom-left pixel: flip rows to image convention.
        self._rgb[:] = self._rgb[::-1]
        np.divide(self._d_coef, self._zbuf[::-1] + self._c_coef, out=self._depth)
        self._frame_key = key
        return self._rgb, self._depth

    def upload_texture(self, model: mujoco.MjModel, texture_id: int) -> None:
        """Sends a texture the model's ``tex_data`` changed to the renderer (a context made later
        reads it from the model anyway), and forgets the cached frame."""
        if self._con is not None:
            self._gl.make_current()
            mujoco.mjr_uploadTexture(model, self._con, texture_id)
        self.invalidate()

    def invalidate(self) -> None:
        """Forgets the cached frame: the scene changed in a way the state does not show
        (bodies moved in the model), so the next read renders again."""
        self._frame_key = None

    def noisy_depth(self, depth: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Applies the stereo noise model to a noise-free depth image (a new array)."""
        c = self.config
        # In place and through take/putmask: the same numbers as the plain expressions, with
        # no temporary frames (a third of the time).
        z = _NORMAL_QUANTILES.take(rng.integers(0, _NORMAL_LEVELS, depth.shape, dtype=np.uint16))
        z *= np.float32(c.depth_noise_k_per_m)
        z *= depth
        z *= depth
        z += depth
        if c.depth_quantum_m > 0:
            q = np.float32(c.depth_quantum_m)
            np.divide(z, q, out=z)
            np.round(z, out=z)
            z *= q
        out_of_range = np.less(depth, c.depth_min_m)
        out_of_range |= np.greater(depth, c.depth_max_m)
        np.putmask(z, out_of_range, 0.0)
        if c.depth_dropout > 0:
            # Draw how many pixels drop out, then where: far cheaper than a uniform per pixel.
            n_drop = rng.binomial(z.size, c.depth_dropout)
            z.ravel()[rng.integers(0, z.size, n_drop)] = 0.0
        return z

    def close(self) -> None:
        if self._con is not None:
            self._con.free()
        if self._gl is not None:
            self._gl.free()
        self._gl = self._con = self._scene = None
        self._frame_key = None


class RGBCamera(Sensor):
    """Colour image of the rig: (H, W, 3) uint8."""

    name = "rgb"
    dtype = np.uint8
    low, high = 0, 255

    def __init__(self, rig: RGBDCameraRig) -> None:
        self.rig = rig
        self.shape = (rig.config.height, rig.config.width, 3)

    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        return self.rig.render(model, data)[0].copy()

    def close(self) -> None:
        self.rig.close()


class DepthCamera(Sensor):
    """Aligned depth of the rig with sensor noise: (H, W, 1) float32 metres, 0 = no return.

    The channel axis makes it an image to RL libraries (stable-baselines3's checker).
    """

    name = "depth"
    dtype = np.float32
    low, high = 0.0, np.inf

    def __init__(self, rig: RGBDCameraRig) -> None:
        self.rig = rig
        self.shape = (rig.config.height, rig.config.width, 1)

    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        return self.rig.noisy_depth(self.rig.render(model, data)[1], rng)[..., None]

    def close(self) -> None:
        self.rig.close()
