"""``racf bench sim``: simulator throughput at the 50 Hz control rate.

Prints control steps per second and the real-time factor (simulated seconds per wall
second) for physics only, physics + LiDAR, and the full sensor set (RGB-D camera, LiDAR,
state, ground truth) at three camera resolutions. The car drives a stop-sign approach at
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

__all__ = ["BenchRow", "bench_sim", "bench_traffic", "TrafficBench"]

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
    return rows


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

    traffic = [c.to_options() for c in cross_traffic(sign, 1.5, cars=cars)]
    envs = {}
    for n in (0, cars):
        env = gym.make(sim.ENV_ID, sensor_profile=sensor_profile, traffic_cars=n)
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
