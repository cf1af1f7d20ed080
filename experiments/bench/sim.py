"""``racf bench sim``: simulator throughput at the 50 Hz control rate.

Prints control steps per second and the real-time factor (simulated seconds per wall
second) for physics only, physics + LiDAR, and the full sensor set (RGB-D camera, LiDAR,
state, ground truth) at three camera resolutions, and the floor at 320 x 240: MuJoCo's bare
physics, one render and readback a frame and the A2M12's rays, each timed alone (what the env
cannot go below without changing what it computes); the CLI prints the full set's ratio to it. The car drives a stop-sign approach at
1 m/s with Stanley lane following, so the camera sees a changing scene.

``bench_traffic`` (``racf bench sim --traffic-cars N``) times the full sensor set at the
default 320 x 240 with and without N other cars crossing at the sign, in alternation in one
process (the machine's drift hits both alike), and prints the ratio of the real-time factors.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from racf import sim
from racf.controllers import StanleyController
from racf.sim.sensors.a2m12 import VISIBLE_GROUPS, A2M12Lidar

__all__ = ["BenchRow", "bench_sim", "bench_traffic", "TrafficBench", "floor_step_s", "full_over_floor", "FLOOR_ROW",
           "RATIO_ROW"]

RESOLUTIONS = ((160, 120), (320, 240), (640, 480))


@dataclass(frozen=True)
class BenchRow:
    setting: str
    steps_per_s: float
    real_time_factor: float


def _drive(env, steps: int, step_fn, options: dict | None = None) -> float:
    """Runs ``steps`` control steps through ``step_fn`` and returns wall seconds."""
    base = env.unwrapped
    sign = base.target_sign
    follower = StanleyController(sign.path.points, sign.path.headings)
    t0 = time.perf_counter()
    for _ in range(steps):
        state = base.car.state(base.data)
        if base.target_sign.path.length - base._route_s < 0.6:  # loop the approach
            env.reset(options=options or {"sign": sign.index, "cruise_speed": 1.0})
            follower.reset()
        step_fn(np.array([1.0, follower.steer(state.x, state.y, state.yaw, state.speed)], np.float32))
    return time.perf_counter() - t0


def bench_sim(steps: int = 250, sign: int = 3, sensor_profile: str = "qcar2") -> list[BenchRow]:
    """Measures each setting on ``sensor_profile``'s sensors; returns one row per setting."""
    rows = []
    control_hz = 50.0

    env = gym.make(sim.ENV_ID, camera_width=160, camera_height=120, sensor_profile=sensor_profile)
    env.reset(seed=0, options={"sign": sign, "cruise_speed": 1.0})
    base = env.unwrapped
    lidar = base.lidar

    def physics(action):
        base.car.apply(base.data, float(action[0]), float(action[1]))
        sim_mujoco.mj_step(base.model, base.data, nstep=base.config.substeps)
        base._update_route_progress()

    def physics_lidar(action):
        # The env's own physics step with the LiDAR (the A2M12 sweeps between physics steps)
        # and no camera frames; the ideal LiDAR casts its whole scan every step.
        base.car.apply(base.data, float(action[0]), float(action[1]))
        base._advance_physics(frames=False)
        if not hasattr(lidar, "has_new_scan") or lidar.has_new_scan():
            lidar.read(base.model, base.data, base._sensor_rng)
        base._update_route_progress()

    import mujoco as sim_mujoco

    for name, fn in (("physics only", physics), ("physics + LiDAR", physics_lidar)):
        env.reset(seed=0, options={"sign": sign, "cruise_speed": 1.0})
        wall = _drive(env, steps, fn)
        rows.append(BenchRow(name, steps / wall, steps / wall / control_hz))
    env.close()

    for width, height in RESOLUTIONS:
        env = gym.make(sim.ENV_ID, camera_width=width, camera_height=height, sensor_profile=sensor_profile)
        env.reset(seed=0, options={"sign": sign, "cruise_speed": 1.0})
        env.step(np.zeros(2, np.float32))  # GL context creation is not part of the rate
        wall = _drive(env, steps, env.step)
        rows.append(BenchRow(f"full sensors {width}x{height}", steps / wall, steps / wall / control_hz))
        env.close()
    floor, ratio = full_over_floor(steps, sign, sensor_profile)
    rows.append(BenchRow(FLOOR_ROW, 1.0 / floor, 1.0 / floor / control_hz))
    rows.append(BenchRow(RATIO_ROW, ratio, ratio))
    return rows


#: The row holding the full set's time a step over the floor's (median of alternating rounds).
RATIO_ROW = "full 320x240 / floor"


def full_over_floor(steps: int, sign: int = 3, sensor_profile: str = "qcar2", rounds: int = 3) -> tuple[float, float]:
    """The floor's seconds a step and the full sensor set's time over it at 320 x 240, each the median
    of ``rounds`` in which the two are timed one after the other (the machine's drift hits both)."""
    import statistics

    env = gym.make(sim.ENV_ID, camera_width=320, camera_height=240, sensor_profile=sensor_profile)
    env.reset(seed=0, options={"sign": sign, "cruise_speed": 1.0})
    env.step(np.zeros(2, np.float32))
    floors, ratios = [], []
    for _ in range(rounds):
        full = _drive(env, steps, env.step) / steps
        floors.append(floor_step_s(steps, sign, sensor_profile))
        ratios.append(full / floors[-1])
    env.close()
    return statistics.median(floors), statistics.median(ratios)


#: The floor's row: what a control step at 320 x 240 cannot cost less than with MuJoCo's own calls.
FLOOR_ROW = "floor 320x240"


def floor_step_s(steps: int, sign: int = 3, sensor_profile: str = "qcar2") -> float:
    """Seconds a control step cannot go below at 320 x 240: MuJoCo's bare physics steps, one render and
    one readback (RGB and depth) a camera frame, and the A2M12's rays for the samples a step casts,
    each timed alone on the same scene; the frame's share is the camera's rate over the control rate."""
    import mujoco

    env = gym.make(sim.ENV_ID, camera_width=320, camera_height=240, sensor_profile=sensor_profile)
    env.reset(seed=0, options={"sign": sign, "cruise_speed": 1.0})
    base = env.unwrapped
    model, data, cfg = base.model, base.data, base.config
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data, nstep=cfg.substeps)
    physics = (time.perf_counter() - start) / steps
    base.rig.render(model, data)  # the GL context is made once, not per frame
    start = time.perf_counter()
    for _ in range(steps):
        base.rig.invalidate()
        base.rig.render(model, data)
    frame = (time.perf_counter() - start) / steps
    rays = 0.0
    lidar = base.lidar
    if isinstance(lidar, A2M12Lidar):  # the picked samples' rays, a step's share of a revolution
        picked = lidar.picked_directions
        per_step = max(1, int(round(picked.shape[0] * lidar.rev_hz / cfg.control_hz)))
        vec = picked[:per_step].reshape(-1, 3).copy()
        m = vec.shape[0]
        site = data.site(lidar.site)
        dist, geom, normal = np.empty(m), np.empty(m, np.int32), np.empty(3 * m)
        start = time.perf_counter()
        for _ in range(steps):
            mujoco.mj_multiRay(model, data, site.xpos.astype(np.float64), vec.ravel(), VISIBLE_GROUPS, 1, -1, geom,
                               dist, normal, m, lidar.config.range_max_m * 2)
        rays = (time.perf_counter() - start) / steps
    env.close()
    camera_hz = cfg.camera_hz if cfg.camera_hz else cfg.control_hz
    return physics + frame * camera_hz / cfg.control_hz + rays


@dataclass(frozen=True)
class TrafficBench:
    """Paired real-time factors of the full sensor set without and with other cars."""

    cars: int
    rtf_empty: tuple[float, ...]
    rtf_traffic: tuple[float, ...]

    @property
    def ratio(self) -> float:
        """Median over the pairs of RTF with traffic / RTF without."""
        return float(np.median(np.array(self.rtf_traffic) / np.array(self.rtf_empty)))


def bench_traffic(cars: int = 2, steps: int = 250, repeats: int = 3, sign: int = 3,
                  sensor_profile: str = "qcar2") -> TrafficBench:
    """The full sensor set (320 x 240) on an approach to ``sign``, without and with ``cars`` other
    cars crossing at its conflict point, timed in alternation ``repeats`` times."""
    from racf.sim.world.traffic import cross_traffic
    from racf.sim.world.traffic_manager import TrafficManager

    traffic = [c.to_options() for c in cross_traffic(sign, 1.5, cars=cars)]
    envs = {}
    for n in (0, cars):
        env = gym.make(sim.ENV_ID, sensor_profile=sensor_profile, world=(TrafficManager(n),) if n else ())
        options = {"sign": sign, "cruise_speed": 1.0, **({"traffic": traffic} if n else {})}
        env.reset(seed=0, options=options)
        env.step(np.zeros(2, np.float32))  # GL context creation is not part of the rate
        envs[n] = (env, options)
    rtf: dict[int, list[float]] = {0: [], cars: []}
    for _ in range(repeats):
        for n, (env, options) in envs.items():
            env.reset(seed=0, options=options)
            rtf[n].append(steps / _drive(env, steps, env.step, options) / 50.0)
    for env, _ in envs.values():
        env.close()
    return TrafficBench(cars, tuple(rtf[0]), tuple(rtf[cars]))
