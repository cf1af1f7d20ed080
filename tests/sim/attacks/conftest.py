"""Shared by the attack wrapper tests: a stub of the racf env, a driver, and the real env where geometry matters.

The stub stands in for ``RACF/QCar2-v4`` wherever the wrapper, not the simulator, is under
test: it has the env's Dict observation space, returns readings that are plain functions
of the distance to the sign and the step, and puts in ``info`` the ground truth the
attacks read. It isolates the wrapper and needs no MuJoCo.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from racf import sim

#: Image size of the stub, pixels.
H, W = 48, 64
N_BEAMS = 360
CONTROL_HZ = 50
#: The sign stands this far past the stop line, m.
STOP_LINE_TO_SIGN_M = 0.5
#: The sign's pixels appear once the stop line is nearer than this, m.
VISIBLE_WITHIN_M = 3.0
#: Where the LiDAR sees the sign, rad CCW from the car's heading; beam i points at i degrees.
SIGN_BEARING_RAD = math.radians(30.0)
SIGN_BEAM = 30
#: The car's heading in the map frame, rad (not 0, so that a beam choice that ignores it fails).
HEADING_RAD = 0.4
#: Beams with no return (inf) in every scan.
NO_RETURN_BEAMS = slice(170, 190)
WALL_RANGE_M = 5.0
SIGN_RGB = (200, 12, 14)


@dataclass(frozen=True)
class StubSign:
    index: int
    position: np.ndarray


@dataclass(frozen=True)
class StubSite:
    xpos: np.ndarray
    xmat: np.ndarray


class StubData:
    """The part of ``mujoco.MjData`` the LiDAR attacks read: ``site("lidar")``."""

    def __init__(self, env: StubEnv) -> None:
        self._env = env

    def site(self, name: str) -> StubSite:
        if name != "lidar":
            raise KeyError(name)
        d = self._env.sign_distance_m
        sign = self._env.target_sign.position
        los = HEADING_RAD + SIGN_BEARING_RAD
        c, s = math.cos(HEADING_RAD), math.sin(HEADING_RAD)
        xmat = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]).ravel()
        return StubSite(xpos=sign - d * np.array([math.cos(los), math.sin(los), 0.0]), xmat=xmat)


class StubEnv(gym.Env):
    """A stand-in for ``RACF/QCar2-v4`` with its observation space (at 64 x 48 px).

    The car moves at the commanded speed (``action[0]``, m/s, clipped to [0, 2]; no dynamics)
    towards a stop line ``run_up_m`` ahead (reset option, default 1.5 m); the sign stands
    ``STOP_LINE_TO_SIGN_M`` past the line. The car slides along its line of sight to the sign,
    so the LiDAR always sees the sign at ``SIGN_BEARING_RAD`` (beam ``SIGN_BEAM``). Readings:

    - ``rgb``: a grey ramp that shifts by one level per step; the sign is a flat red disc
      centred in the image, radius 12 px / sign distance (m), once the line is nearer than
      ``VISIBLE_WITHIN_M``;
    - ``depth``: a wall at 4 m minus 1 cm per column, no return (0) on the top 4 rows; the
      sign's pixels at ``d_true`` except a lattice of holes (0) on a fifth of them;
    - ``lidar``: the wall at ``WALL_RANGE_M``, inf on ``NO_RETURN_BEAMS``, the sign's distance
      on beam ``SIGN_BEAM``;
    - ``gps``: the car on the x axis, ``dist`` short of the line; ``state``: the speed, then
      zeros; ``timestamps``: every reading taken now.

    ``info`` has ``time``, ``sign_mask``, ``sign_in_view``, ``d_true``, ``dist_to_stop_line``
    and ``speed``; ``target_sign.position`` and ``data.site("lidar")`` give the geometry the
    LiDAR attacks read, and ``sensor_observation()`` the readings before any wrapper, like the
    real env.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": [], "render_fps": CONTROL_HZ}

    def __init__(self) -> None:
        self.observation_space = spaces.Dict({
            "rgb": spaces.Box(0, 255, (H, W, 3), np.uint8),
            "depth": spaces.Box(0.0, np.inf, (H, W, 1), np.float32),
            "lidar": spaces.Box(0.0, np.inf, (N_BEAMS,), np.float32),
            "gps": spaces.Box(-np.inf, np.inf, (3,), np.float32),
            "state": spaces.Box(-np.inf, np.inf, (4,), np.float32),
            "timestamps": spaces.Box(0.0, np.inf, (5,), np.float64),
        })
        self.action_space = spaces.Box(np.array([-1.0, -0.5], np.float32), np.array([2.0, 0.5], np.float32),
                                       dtype=np.float32)
        self.target_sign = StubSign(0, np.array([3.0, 2.0, 0.3]))
        self.data = StubData(self)
        self._dist, self._speed, self._step = 1.5, 1.0, 0

    @property
    def sign_distance_m(self) -> float:
        return self._dist + STOP_LINE_TO_SIGN_M

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"sign", "cruise_speed", "run_up_m"}
        if unknown:
            raise ValueError(f"unknown reset option(s) {sorted(unknown)}")
        self._dist = float(options.get("run_up_m", 1.5))
        self._speed = float(options.get("cruise_speed", 1.0))
        self._step = 0
        return self.sensor_observation(), self._info()

    def step(self, action):
        self._speed = float(np.clip(action[0], 0.0, 2.0))
        self._dist -= self._speed / CONTROL_HZ
        self._step += 1
        return self.sensor_observation(), 0.0, self._dist <= 0.0, self._step >= 500, self._info()

    def sign_mask(self) -> np.ndarray:
        """(H, W) bool: the sign's pixels."""
        if not 0.0 < self._dist < VISIBLE_WITHIN_M:
            return np.zeros((H, W), bool)
        radius = min(12.0 / self.sign_distance_m, 20.0)
        rows, cols = np.mgrid[:H, :W]
        return (rows - H // 2) ** 2 + (cols - W // 2) ** 2 <= radius**2

    def sensor_observation(self) -> dict[str, np.ndarray]:
        mask = self.sign_mask()
        rows, cols = np.mgrid[:H, :W]
        grey = ((rows + 2 * cols + self._step) % 200 + 30).astype(np.uint8)
        rgb = np.repeat(grey[..., None], 3, axis=2)
        rgb[mask] = SIGN_RGB
        depth = (4.0 - 0.01 * cols).astype(np.float32)
        depth[:4] = 0.0
        depth[mask] = self.sign_distance_m
        depth[mask & ((rows + 2 * cols) % 5 == 0)] = 0.0
        lidar = np.full(N_BEAMS, WALL_RANGE_M, np.float32)
        lidar[NO_RETURN_BEAMS] = np.inf
        lidar[SIGN_BEAM] = self.sign_distance_m
        state = np.array([self._speed, 0.0, 0.0, 0.0], np.float32)
        gps = np.array([-self._dist, 0.0, 0.0], np.float32)
        stamps = np.full(5, self._step / CONTROL_HZ)
        return {"rgb": rgb, "depth": depth[..., None], "lidar": lidar, "gps": gps, "state": state,
                "timestamps": stamps}

    def _info(self) -> dict[str, Any]:
        mask = self.sign_mask()
        return {"time": self._step / CONTROL_HZ, "sign_mask": mask, "sign_in_view": bool(mask.any()),
                "d_true": self.sign_distance_m, "dist_to_stop_line": self._dist, "speed": self._speed}


def _drive(env: gym.Env, steps: int, seed: int = 0, options: dict[str, Any] | None = None
           ) -> Iterator[tuple[dict, dict, dict]]:
    """Drives straight at 1 m/s; yields (obs, clean obs, info) per step.

    ``options`` default to a 1.5 m run-up at 1 m/s (add ``sign`` for the real env).
    """
    options = {"cruise_speed": 1.0, "run_up_m": 1.5, **(options or {})}
    env.reset(seed=seed, options=options)
    for _ in range(steps):
        obs, _, term, trunc, info = env.step(np.array([1.0, 0.0], np.float32))
        yield obs, env.unwrapped.sensor_observation(), info
        if term or trunc:
            return


def _grown(mask: np.ndarray, px: int) -> np.ndarray:
    """(H, W) bool: ``mask`` grown by ``px`` pixels in every direction, diagonals included."""
    out = mask.copy()
    padded = np.pad(mask, px)
    for dy in range(2 * px + 1):
        for dx in range(2 * px + 1):
            out |= padded[dy:dy + mask.shape[0], dx:dx + mask.shape[1]]
    return out


@pytest.fixture
def stub_env() -> Iterator[Callable[[], StubEnv]]:
    """Makes stub envs; closes them after the test."""
    made: list[StubEnv] = []

    def make() -> StubEnv:
        made.append(StubEnv())
        return made[-1]
    yield make
    for env in made:
        env.close()


@pytest.fixture
def real_env() -> Iterator[Callable[[], gym.Env]]:
    """Makes the real env at 160 x 120 px, for checks that need its geometry; closes them after the test."""
    made: list[gym.Env] = []

    def make() -> gym.Env:
        made.append(gym.make(sim.ENV_ID, camera_width=160, camera_height=120))
        return made[-1]
    yield make
    for env in made:
        env.close()


@pytest.fixture
def drive() -> Callable[..., Iterator[tuple[dict, dict, dict]]]:
    """``drive(env, steps, seed=0, options=None)``: yields (obs, clean obs, info) per step at 1 m/s."""
    return _drive


@pytest.fixture
def grown() -> Callable[[np.ndarray, int], np.ndarray]:
    """``grown(mask, px)``: the mask grown by ``px`` pixels (a square neighbourhood)."""
    return _grown
