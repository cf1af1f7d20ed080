"""``racf export-bag``: an episode as a rosbag2 (MCAP) on Quanser's topics.

The episode is run again from its spec (its id makes that reproducible: the same spec, configs
and code give the same steps), and each reading the car's software received is written when it
arrived: a message's log time is the 50 Hz step at which the car first had it, its header stamp
when the sensor took it. The bag is written into a temporary folder beside the target and
renamed when whole, so an interrupted export leaves nothing half-written.
"""

from __future__ import annotations

import json
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from racf.errors import UserError
from racf.experiments.bags import messages as m
from racf.experiments.bags.topics import (CAR_PREFIX, QUANSER_TOPICS, RACF_TOPICS, SCAN_DELIVERED, SCAN_TIMES,
                                          SIGN_MASK, SPEC_KEY, TRUTH_PREFIX, typestore)
from racf.experiments.episode.plan import plan_episode
from racf.experiments.episode.record import CAR, REFEREE, STEP_LOG
from racf.experiments.episode.spec import TrialSpec
from racf.sim.sensors import TIMESTAMP_FIELDS
from racf.sim.sensors.a2m12 import A2M12Lidar, driver_scan
from racf.sim.sensors.state import OdometryConfig
from racf.sim.sensors.calibration import car_build

__all__ = ["BagWriter", "ExportSummary", "export_episode", "DELIVERED_TIMES"]

#: Per-bin times of ``/racf/scan/delivered``.
DELIVERED_TIMES = "/racf/scan/delivered_times"
_Q, _R = QUANSER_TOPICS, RACF_TOPICS


class BagWriter:
    """A rosbag2 in MCAP (zstd-compressed chunks), its connections made on first use; written under
    a hidden folder beside ``path`` and moved to ``path`` by :meth:`close`."""

    def __init__(self, path: Path, custom: dict[str, str] | None = None) -> None:
        from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

        self.path = Path(path)
        if self.path.exists():
            raise UserError(f"{self.path} exists; remove it or choose another path for the bag")
        # rosbag2 names its file after the folder: write <parent>/.<name>.partial/<name>, then move it.
        self._scratch = self.path.parent / f".{self.path.name}.partial"
        shutil.rmtree(self._scratch, ignore_errors=True)
        self._scratch.mkdir(parents=True)
        self._writer = Writer(self._scratch / self.path.name, version=9, storage_plugin=StoragePlugin.MCAP)
        # zstd chunks inside the MCAP file (what ros2 bag's "storage" compression writes).
        self._writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        for key, value in (custom or {}).items():
            self._writer.set_custom_data(key, value)
        self._writer.open()
        self._store = typestore()
        self._connections: dict[str, object] = {}
        self.counts: dict[str, int] = {}

    def write(self, topic: str, msgtype: str, t_ns: int, msg) -> None:
        conn = self._connections.get(topic)
        if conn is None:
            conn = self._connections[topic] = self._writer.add_connection(topic, msgtype, typestore=self._store)
        self._writer.write(conn, t_ns, self._store.serialize_cdr(msg, msgtype))
        self.counts[topic] = self.counts.get(topic, 0) + 1

    def close(self) -> Path:
        self._writer.close()
        (self._scratch / self.path.name).rename(self.path)
        self._scratch.rmdir()
        return self.path

    def abort(self) -> None:
        try:
            self._writer.close()
        finally:
            shutil.rmtree(self._scratch, ignore_errors=True)


@dataclass(frozen=True)
class ExportSummary:
    """What an export wrote: the bag, the episode's result row, its steps and each topic's count, and
    the episode's own step log (what a replay of the bag should give back)."""

    path: Path
    trial_id: str
    steps: int
    duration_s: float
    counts: dict[str, int]
    result: dict
    log: object = None


def _numeric(value) -> bool:
    return isinstance(value, (bool, int, float, np.bool_, np.integer, np.floating))


class _Recorder:
    """The episode's step hook: writes what arrived at each step."""

    def __init__(self, writer: BagWriter, spec: TrialSpec) -> None:
        self.w = writer
        self.plan = plan_episode(spec)
        self.step_ns = int(round(self.plan.control_dt_s * 1e9))
        self.m_per_count = OdometryConfig().m_per_count
        self.k = 0
        self.last: dict[str, float] = {}
        self.encoder_counts = 0.0

    def _new(self, key: str, stamp: float) -> bool:
        if self.last.get(key) == stamp:
            return False
        self.last[key] = stamp
        return True

    def __call__(self, env, obs: dict, info: dict, row: dict) -> None:
        t = self.k * self.step_ns
        u = env.unwrapped
        stamps = dict(zip(TIMESTAMP_FIELDS, (float(s) for s in obs["timestamps"])))
        if self.k == 0:
            self._static(u, t)
        if self._new("rgb", stamps["rgb"]):
            ts = m.ns_of(stamps["rgb"])
            self.w.write(_Q["rgb"].name, _Q["rgb"].msgtype, t, m.image_msg(obs["rgb"], ts))
            k = u.rig.intrinsics
            self.w.write(_R["camera_info"].name, _R["camera_info"].msgtype, t,
                         m.camera_info_msg(k.width, k.height, k.fx, k.fy, k.cx, k.cy, ts))
            if "sign_mask" in info:
                self.w.write(SIGN_MASK, _R["sign_mask"].msgtype, t, m.mask_msg(info["sign_mask"], ts))
        if self._new("depth", stamps["depth"]):
            self.w.write(_Q["depth"].name, _Q["depth"].msgtype, t,
                         m.depth_msg(obs["depth"][..., 0], m.ns_of(stamps["depth"])))
        if self._new("lidar", stamps["lidar"]):
            self._scan(u, obs, m.ns_of(stamps["lidar"]), t)
        if self._new("state", stamps["state"]):
            ts = m.ns_of(stamps["state"])
            speed, _, yaw_rate, accel = (float(v) for v in obs["state"])
            self.w.write(_Q["imu"].name, _Q["imu"].msgtype, t, m.imu_msg(yaw_rate, accel, ts))
            per_s = speed / self.m_per_count
            self.encoder_counts += per_s * self.plan.control_dt_s
            self.w.write(_Q["joint"].name, _Q["joint"].msgtype, t,
                         m.joint_msg(float(round(self.encoder_counts)), per_s, ts))
        if self._new("gps", stamps["gps"]):
            self.w.write(_R["fix"].name, _R["fix"].msgtype, t, m.pose_msg(*obs["gps"], m.ns_of(stamps["gps"])))
        self.w.write(_Q["command"].name, _Q["command"].msgtype, t,
                     m.command_msg(float(row["steer_cmd"]), float(row["speed_cmd"])))
        self.w.write(_R["tf"].name, _R["tf"].msgtype, t,
                     m.tf_msg([("map", "base_link", (row["x_est"], row["y_est"], 0.0), row["yaw_est"])], t))
        self._signals(row, t)
        self.k += 1

    def _static(self, u, t: int) -> None:
        calib = self.plan.calibration
        build = car_build(u.rig.intrinsics.width, u.rig.intrinsics.height)
        lx, ly = calib.lidar_xy_m
        cx, cy = calib.camera_xy_m
        transforms = [("base_link", "base_scan", (lx, ly, build.lidar_height_m), math.pi),
                      ("base_link", "color_image", (cx, cy, calib.camera_height_m), 0.0),
                      ("base_link", "depth_image", (cx, cy, calib.camera_height_m), 0.0)]
        self.w.write(_R["tf_static"].name, _R["tf_static"].msgtype, t, m.tf_msg(transforms, t))

    def _scan(self, u, obs: dict, ts: int, t: int) -> None:
        lidar = u.lidar
        if isinstance(lidar, A2M12Lidar):
            ranges, times = lidar.samples
            c = lidar.config
            self.w.write(_Q["scan"].name, _Q["scan"].msgtype, t, m.scan_msg(ranges, ts, lidar.rev_hz, c.range_max_m))
            self.w.write(SCAN_TIMES, _R["scan_times"].msgtype, t, m.array_msg(times))
            delivered = driver_scan(ranges, times, c.read_per_rev, c.n_bins, c.max_gap_deg)[0]
        else:  # the ideal LiDAR: its bins at one instant, as a scan of as many samples
            bins = np.asarray(obs["lidar"], np.float64)
            n = bins.size
            order = (n // 2 - np.arange(n)) % n  # sample i at i bins clockwise from the car's rear
            ranges = np.where(np.isfinite(bins[order]), bins[order], 0.0)
            self.w.write(_Q["scan"].name, _Q["scan"].msgtype, t, m.scan_msg(ranges, ts, 10.0, 12.0))
            self.w.write(SCAN_TIMES, _R["scan_times"].msgtype, t, m.array_msg(obs["lidar_beam_times"][order]))
            delivered = np.where(ranges[np.argsort(order)] > 0, ranges[np.argsort(order)], np.inf).astype(np.float32)
        if not np.array_equal(delivered, obs["lidar"]):  # an attack changed the scan after the driver
            self.w.write(SCAN_DELIVERED, _R["scan_delivered"].msgtype, t, m.bins_msg(obs["lidar"], ts))
            self.w.write(DELIVERED_TIMES, _R["scan_times"].msgtype, t, m.array_msg(obs["lidar_beam_times"]))

    def _signals(self, row: dict, t: int) -> None:
        for name, value in row.items():
            column = STEP_LOG.get(name)
            if not _numeric(value) or name in ("t", "scan_fov") or (isinstance(value, float) and math.isnan(value)):
                continue  # NaN: nothing to say this step (no target, no such car)
            if name == "attack_active":
                topic = _R["attack_active"].name
            elif column is not None and column.side == REFEREE:
                topic = TRUTH_PREFIX + name
            elif column is None or column.side == CAR:  # the estimator's own diagnostics are the car's
                topic = CAR_PREFIX + name
            else:
                continue
            self.w.write(topic, "std_msgs/msg/Float64", t, m.float_msg(float(value)))


def export_episode(spec: TrialSpec, path: Path) -> ExportSummary:
    """Runs ``spec`` again and writes it to the bag folder ``path`` (which must not exist)."""
    from racf.experiments.episode import run_trial

    path = Path(path)
    writer = BagWriter(path, {SPEC_KEY: json.dumps(spec.to_dict(), default=str), "racf.trial_id": spec.trial_id})
    recorder = _Recorder(writer, spec)
    try:
        result, log = run_trial(spec, on_step=recorder)
    except BaseException:
        writer.abort()
        raise
    out = writer.close()
    return ExportSummary(out, spec.trial_id, len(log), float(log["t"].iloc[-1]), dict(writer.counts),
                         result.to_dict(), log)
