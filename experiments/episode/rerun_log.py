"""Episodes as rerun recordings (``.rrd``), replayed from the per-step log, off the hot path.

:class:`FrameRecorder` is a step hook for :func:`racf.experiments.episode.run_trial`: it keeps
what the per-step log does not hold (camera and depth frames, the full LiDAR scan, the
camera pose, the patch's box) every ``every`` steps and nothing else. :func:`write_rrd`
then replays the log and those frames into a recording on the ``sim_time`` timeline:

- ``world/camera``: the D435 at its pose (``Pinhole``) with ``image`` (plus the detection box
  and, while active, the patch) and ``depth`` (``DepthImage``);
- ``world/car/lidar``: the LiDAR returns in the car's frame, the tracked reference's
  cluster in red, and ``world/car/lidar/track`` the tracked point;
- ``map``: a top view of the mat with the car's trajectory and its current position, and the
  world's other actors (``map/actors/NAME``): the paths and current positions of those that move
  (other cars, a person) and the places of those that stay put (a conflict point);
- ``world/actors/NAME``: each moving actor's body, a car's box where it has a heading (ground truth:
  the ``NAME_x``/``NAME_y``/``NAME_yaw`` columns a world manager logs);
- ``series/*`` (d_true, d_clean, d_meas, lidar, d_fused, and ODCA's d_kin; NaN, where an
  estimator has no target, is a gap), ``control/*`` (gate w, the defence's flag, brake, attack
  active) and ``estimator/*`` (whatever else the estimator, a plug-in's too, reports in
  ``diagnostics()``), every step, sent with ``send_columns``; ``existence/*``: a defence that
  answers whether a sign stands (``vote``, ``detectors_or``, ``map_only``) logs each witness
  (``wit_det0``/``wit_det1`` the detectors at the hypothesis, ``wit_depth`` the plate in the depth
  image, ``wit_lidar``, ``wit_blind``, ``wit_map``, ``wit_moving`` the depth caught moving by the
  static-world check) and its verdict ``stands``;
- ``stages/NAME/*``: the distance series each car stage declares (``CarStage.series``: the car ahead
  from the camera as each witness sees it and the defence's, for one) where its columns are in the
  log, beside ``stages/truth/TARGET``: each declared target's true depth (``WorldTarget``).

A default blueprint lays these out so the story reads at a glance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from racf.experiments.episode.record import STEP_LOG
from racf.sim.world.manager import QCAR2_BOX_M, world_targets

__all__ = ["FrameRecorder", "write_rrd", "EXISTENCE_COLUMNS", "SERIES", "CONTROL", "STYLE", "stage_series", "CAR_HALF_SIZE_M",
           "ACTOR_RGB", "actors", "target_depth_true"]

#: The step-log columns of an existence defence's witnesses (``ExistenceWitnesses.columns``, ``stands``).
EXISTENCE_COLUMNS = ("wit_", "seen_det", "map_depth_m", "stands")
#: Distance series (metres) and control series, as logged (entity name -> log column).
SERIES = {"d_true": "d_true", "d_clean": "d_clean", "d_meas": "d_meas", "lidar": "lidar", "d_fused": "d_fused",
          "d_kin": "d_kin"}
CONTROL = {"gate_w": "w", "flag": "flag", "brake": "brake", "attack_active": "attack_active"}
#: Each series' colour (RGB) and legend name: one hue family per kind of signal, no two alike.
STYLE: dict[str, tuple[tuple[int, int, int], str]] = {
    "d_true": ((40, 40, 40), "d_true (ground truth, sign in view)"),
    "d_clean": ((44, 160, 44), "d_clean (perception, unattacked)"),
    "d_meas": ((214, 39, 40), "d_meas (depth camera)"),
    "lidar": ((23, 190, 207), "LiDAR reference"),
    "d_fused": ((31, 119, 180), "d_fused (what the car brakes on)"),
    "d_kin": ((148, 103, 189), "d_kin (ODCA's kinematic branch)"),
    "gate_w": ((255, 127, 14), "gate w (ODCA's repair weight)"),
    "flag": ((227, 119, 194), "flag (the defence's detector)"),
    "brake": ((140, 86, 75), "brake"),
    "attack_active": ((188, 189, 34), "attack active"),
    "target_true": ((110, 110, 110), "a declared target's rear (ground truth)"),
}
#: A car's body (a QCar 2's box), centred over the axles' midpoint, m.
CAR_HALF_SIZE_M = tuple(v / 2 for v in QCAR2_BOX_M)
#: The world's other actors' colours on the map and in 3D, in the order of their names (the first four
#: are the other cars' paint: red, blue, yellow, white).
ACTOR_RGB = ((200, 20, 20), (25, 65, 190), (230, 190, 25), (235, 235, 235), (240, 130, 20), (120, 60, 160))
_CAR_CENTRE_Z_M = 0.10


def target_depth_true(log: pd.DataFrame, target) -> np.ndarray:
    """(n,) a declared target's rear (``WorldTarget``: its pose columns, half its length behind its
    centre) along the camera's optical axis, from the true poses, m (NaN: not in the world)."""
    from racf.experiments.episode.plan import car_calibration

    cx, cy = car_calibration(320, 240).camera_xy_m
    c, s = np.cos(log["yaw"].to_numpy(float)), np.sin(log["yaw"].to_numpy(float))
    cam_x = log["x"].to_numpy(float) + c * cx - s * cy
    cam_y = log["y"].to_numpy(float) + s * cx + c * cy
    x, y, yaw = (log[column].to_numpy(float) for column in target.pose_columns)
    rear_x = x - np.cos(yaw) * target.size_m[0] / 2
    rear_y = y - np.sin(yaw) * target.size_m[0] / 2
    return c * (rear_x - cam_x) + s * (rear_y - cam_y)


def _target_truths(log: pd.DataFrame, targets) -> tuple[pd.DataFrame, dict]:
    """The log with each declared target's true depth (``<name>_depth_true``), and their series."""
    series = {}
    for target in targets:
        if not {*target.pose_columns, "x"} <= set(log.columns) or not np.isfinite(log[target.pose_columns[0]]
                                                                                    .to_numpy(float)).any():
            continue
        column = f"{target.name}_depth_true"
        log = log.assign(**{column: target_depth_true(log, target)})
        series[f"stages/truth/{target.name}"] = (column, (STYLE["target_true"][0], f"the {target.name}'s rear "
                                                                                   "(ground truth)"))
    return log, series


def stage_series(log: pd.DataFrame) -> dict[str, tuple[str, tuple]]:
    """The car stages' distance series in ``log`` (``CarStage.series`` of every registered stage whose
    columns it holds): entity path -> (column, (colour, legend))."""
    from racf.plugins import CAR_STAGES

    return {f"stages/{name}/{column}": (column, style) for name in CAR_STAGES
            for column, style in CAR_STAGES[name].series.items() if column in log.columns}


def _shown(log: pd.DataFrame, column: str) -> np.ndarray:
    """The column as drawn: NaN (a gap) where the quantity is undefined. d_true only while the sign
    is in view (out of view it is not what the car is approaching); the gate and the flag only
    while the defence has a target."""
    values = log[column].to_numpy(float).copy()
    if column == "d_true" and "sign_in_view" in log:
        values[~log["sign_in_view"].to_numpy(bool)] = np.nan
    if column in ("w", "flag") and "d_fused" in log:
        values[~np.isfinite(log["d_fused"].to_numpy(float))] = np.nan
    return values
_MAP_PX_PER_M = 60
#: A LiDAR return belongs to the tracked cluster within this distance of the tracked point, m.
_CLUSTER_RADIUS_M = 0.12


@dataclass(frozen=True)
class Frame:
    t: float
    rgb: np.ndarray  # (H, W, 3) uint8, as the controller saw it
    depth_mm: np.ndarray  # (H, W) uint16, 0 = no return
    lidar: np.ndarray  # (N,) float32 ranges, inf = no return
    cam_pos: np.ndarray  # (3,) map frame
    cam_mat: np.ndarray  # (3, 3) camera-to-map (MuJoCo camera axes: x right, y up, z backward)
    patch_box: tuple[int, int, int, int] | None  # x0, y0, x1, y1 of the patched pixels


class FrameRecorder:
    """Step hook keeping one frame every ``every`` steps (default 5: 10 Hz at 50 Hz control)."""

    def __init__(self, every: int = 5) -> None:
        if not (isinstance(every, int) and every >= 1):
            raise ValueError(f"every must be an int >= 1, got {every!r}")
        self.every = every
        self.frames: list[Frame] = []
        self.intrinsics = None
        self._step = 0

    def __call__(self, env, obs: dict, info: dict, row: dict) -> None:
        u = env.unwrapped
        if self.intrinsics is None:
            self.intrinsics = u.rig.intrinsics
        if self._step % self.every == 0:
            cam_pos, cam_mat = u.car.camera_pose(u.model, u.data)
            patch = None
            if row["attack_active"]:
                changed = np.any(obs["rgb"] != u.sensor_observation()["rgb"], axis=-1)
                if changed.any():
                    rows, cols = np.nonzero(changed)
                    patch = (int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1)
            depth = obs["depth"][..., 0]
            self.frames.append(Frame(float(row["t"]), obs["rgb"].copy(),
                                     np.clip(np.rint(depth * 1000.0), 0, 65535).astype(np.uint16),
                                     np.asarray(obs["lidar"], np.float32).copy(), cam_pos, cam_mat, patch))
        self._step += 1


def _blueprint():
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial2DView(origin="world/camera", contents=["world/camera/image", "world/camera/image/**"],
                                  name="camera (detection green, patch magenta)"),
                rrb.Spatial2DView(origin="world/camera", contents=["world/camera/depth"], name="depth"),
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="series", name="distances (m)"),
                rrb.TimeSeriesView(origin="control", name="gate w, brake, attack"),
                rrb.TimeSeriesView(origin="existence", name="existence witnesses (1: says a sign stands)"),
                rrb.TimeSeriesView(origin="stages", name="the car's stages (m from the camera)"),
            ),
            rrb.Vertical(
                rrb.Spatial2DView(origin="map", name="map (top view)"),
                rrb.Spatial3DView(origin="world", name="car, camera and LiDAR"),
            ),
            column_shares=[2, 2, 2],
        ),
        collapse_panels=True,
    )


def _map_px(xy: np.ndarray) -> np.ndarray:
    from racf.sim.world import map_facts

    x0, _, _, y1 = map_facts.WALL_BOUNDS_M
    xy = np.atleast_2d(np.asarray(xy, float))
    return np.column_stack([(xy[:, 0] - x0) * _MAP_PX_PER_M, (y1 - xy[:, 1]) * _MAP_PX_PER_M])


def recorded_trial(spec, rrd: str | Path | None = None, title: str = "racf episode", clean_pass: bool = True):
    """``run_trial(spec)``, recorded to the rerun file ``rrd`` (its folder made) unless it is None;
    returns (result, log)."""
    from racf.experiments.episode import run_trial

    recorder = FrameRecorder() if rrd is not None else None
    result, log = run_trial(spec, on_step=recorder, clean_pass=clean_pass)
    if recorder is not None:
        Path(rrd).parent.mkdir(parents=True, exist_ok=True)
        targets = world_targets(spec.scenario.world(spec, spec.scenario_params))
        write_rrd(rrd, log, recorder, title=title, targets=targets)
    return result, log


def write_rrd(path: str | Path, log: pd.DataFrame, recorder: FrameRecorder | None = None,
              title: str = "racf episode", targets=()) -> Path:
    """Writes the episode (``log`` from ``run_trial``, frames from ``recorder``) to ``path``; returns it.
    ``targets``: the world's declared targets (``WorldTarget``), whose true depth is drawn beside the
    car's stages' series."""
    import rerun as rr

    from racf.controllers.lidar_target import LidarTargetConfig
    from racf.experiments.episode.record import STEP_LOG
    from racf.sim.world.mat_texture import render_mat
    from racf.sim.world.stop_signs import stop_signs

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if log.empty:
        raise ValueError("the episode log is empty: nothing to record")
    rec = rr.RecordingStream("racf", recording_id=title)
    rec.save(str(path), default_blueprint=_blueprint())

    # Static: the map's top view, the stop signs, the whole trajectory; the 3D world is z up.
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log("map/mat", rr.Image(render_mat(px_per_m=_MAP_PX_PER_M)), static=True)
    signs = stop_signs()
    rec.log("map/stop_signs", rr.Points2D(_map_px([s.position for s in signs]), radii=4, colors=[200, 20, 20],
                                          labels=[f"stop {s.index}" for s in signs]), static=True)
    # A replayed recording has no ground truth: its pose is the car's own estimate.
    pose = ("x", "y", "yaw") if "x" in log else ("x_est", "y_est", "yaw_est")
    if "x" in log:
        rec.log("map/trajectory", rr.LineStrips2D([_map_px(log[["x", "y"]].to_numpy(float))], colors=[30, 120, 230],
                                                  radii=1.5, labels=["true pose"]), static=True)
    moving, still = actors(log)
    for k, name in enumerate(moving):
        rec.log(f"map/actors/{name}/path", rr.LineStrips2D([_map_px(log[[f"{name}_x", f"{name}_y"]].to_numpy(float))],
                                                           colors=[ACTOR_RGB[k % len(ACTOR_RGB)]], radii=1.0,
                                                           labels=[name]), static=True)
    for name in still:
        place = log[[f"{name}_x", f"{name}_y"]].dropna().iloc[0].to_numpy(float)
        rec.log(f"map/actors/{name}", rr.Points2D(_map_px(place), radii=6, colors=[255, 200, 0], labels=[name]),
                static=True)
    if {"x_est", "y_est"} <= set(log.columns):  # the car's own pose estimate, beside the truth
        est = log[["x_est", "y_est"]].to_numpy(float)
        rec.log("map/trajectory_estimate", rr.LineStrips2D([_map_px(est)], colors=[240, 120, 20], radii=1.0,
                                                           labels=["car's estimate"]), static=True)

    # Every step: the signals, as columns.
    times = rr.TimeColumn("sim_time", duration=log["t"].to_numpy(float))
    staged = stage_series(log)
    shown = set(SERIES.values()) | set(CONTROL.values()) | {column for column, _ in staged.values()}
    own = {f"{'existence' if c.startswith(EXISTENCE_COLUMNS) else 'estimator'}/{c}": c for c in log.columns
           # the estimator's diagnostics beyond the declared log; an existence defence's witnesses apart
           if c not in STEP_LOG and c not in shown and pd.api.types.is_numeric_dtype(log[c])}
    log, truths = _target_truths(log, targets)
    staged |= truths
    styles = {**{f"series/{k}": (v, STYLE.get(k)) for k, v in SERIES.items()},
              **{f"control/{k}": (v, STYLE.get(k)) for k, v in CONTROL.items()},
              **{name: (column, None) for name, column in own.items()}, **staged}
    for name, (column, style) in styles.items():
        if column in log:
            if style is not None:
                colour, legend = style
                rec.log(name, rr.SeriesLines(colors=[colour], names=[legend]), static=True)
            rec.send_columns(name, indexes=[times], columns=rr.Scalars.columns(scalars=_shown(log, column)))

    if recorder is not None and recorder.frames:
        k = recorder.intrinsics
        rec.log("world/camera", rr.Pinhole(focal_length=[k.fx, k.fy], principal_point=[k.cx, k.cy], width=k.width,
                                           height=k.height, camera_xyz=rr.ViewCoordinates.RUB,
                                           image_plane_distance=0.3), static=True)
        lidar_cfg = LidarTargetConfig()
        rec.log("world/car/body", rr.Boxes3D(half_sizes=[CAR_HALF_SIZE_M], centers=[[0.0, 0.0, _CAR_CENTRE_Z_M]],
                                             colors=[[60, 60, 70]], labels=["QCar 2"]), static=True)
        by_t = log.set_index("t")
        for frame in recorder.frames:
            row = by_t.loc[frame.t]
            rec.set_time("sim_time", duration=frame.t)
            rec.log("world/camera", rr.Transform3D(translation=frame.cam_pos, mat3x3=frame.cam_mat))
            rec.log("world/camera/image", rr.Image(frame.rgb).compress(jpeg_quality=80))
            rec.log("world/camera/depth", rr.DepthImage(frame.depth_mm, meter=1000.0, colormap="turbo"))
            if row["detected"]:
                rec.log("world/camera/image/detection", rr.Boxes2D(
                    array=[[row["det_x0"], row["det_y0"], row["det_x1"], row["det_y1"]]],
                    array_format=rr.Box2DFormat.XYXY, colors=[0, 230, 0], labels=["detection"]))
            else:
                rec.log("world/camera/image/detection", rr.Clear(recursive=False))
            if frame.patch_box is not None:
                rec.log("world/camera/image/patch", rr.Boxes2D(array=[frame.patch_box],
                                                               array_format=rr.Box2DFormat.XYXY,
                                                               colors=[230, 0, 230], labels=["patch"]))
            else:
                rec.log("world/camera/image/patch", rr.Clear(recursive=False))
            x, y, yaw = (float(row[c]) for c in pose)
            rec.log("world/car", rr.Transform3D(translation=[x, y, 0.0],
                                                rotation=rr.RotationAxisAngle(axis=[0, 0, 1], radians=yaw)))
            rec.log("map/car", rr.Points2D(_map_px([x, y]), radii=5, colors=[255, 160, 0]))
            _log_actors(rec, row, moving)
            _log_lidar(rec, frame.lidar, row, lidar_cfg)
    rec.flush()
    rec.disconnect()
    return path


def actors(log: pd.DataFrame) -> tuple[list[str], list[str]]:
    """The world's other actors the log places: every ``NAME_x``/``NAME_y`` pair of columns that racf's own
    step log does not declare (a world manager's: other cars, a person, a conflict point) and that holds a
    position. Those that move (drawn at every frame) and those that stay put (drawn once), by name."""
    moving, still = [], []
    for column in log.columns:
        name = str(column)[:-2]
        if not str(column).endswith("_x") or column in STEP_LOG or f"{name}_y" not in log or f"{name}_y" in STEP_LOG:
            continue
        xy = log[[column, f"{name}_y"]].to_numpy(float)
        xy = xy[np.isfinite(xy).all(axis=1)]
        if len(xy):
            (moving if (xy != xy[0]).any() else still).append(name)
    return sorted(moving), sorted(still)


def _log_actors(rec, row, moving: list[str]) -> None:
    """Each moving actor in the world and on the map at this step: a car's box where it has a heading
    (``NAME_yaw``), else a post of a person's height."""
    import rerun as rr

    for k, name in enumerate(moving):
        x, y = float(row[f"{name}_x"]), float(row[f"{name}_y"])
        colour = ACTOR_RGB[k % len(ACTOR_RGB)]
        if not (math.isfinite(x) and math.isfinite(y)):
            rec.log(f"world/actors/{name}", rr.Clear(recursive=False))
            continue
        yaw = row.get(f"{name}_yaw")
        if yaw is not None and math.isfinite(float(yaw)):
            rec.log(f"world/actors/{name}", rr.Boxes3D(half_sizes=[CAR_HALF_SIZE_M], centers=[[x, y, _CAR_CENTRE_Z_M]],
                                                       rotation_axis_angles=[rr.RotationAxisAngle(axis=[0, 0, 1],
                                                                                                  radians=float(yaw))],
                                                       colors=[colour], labels=[name]))
        else:
            rec.log(f"world/actors/{name}", rr.Boxes3D(half_sizes=[[0.02, 0.02, 0.09]], centers=[[x, y, 0.09]],
                                                       colors=[colour], labels=[name]))
        rec.log(f"map/actors/{name}/now", rr.Points2D(_map_px([x, y]), radii=5, colors=[colour]))


def _log_lidar(rec, ranges: np.ndarray, row, cfg) -> None:
    """Returns in the car's body frame; the tracked reference's cluster in red."""
    import rerun as rr

    angles = np.arange(len(ranges)) * (2 * np.pi / len(ranges))
    ok = np.isfinite(ranges)
    pts = np.column_stack([cfg.lidar_position_m[0] + ranges[ok] * np.cos(angles[ok]),
                           cfg.lidar_position_m[1] + ranges[ok] * np.sin(angles[ok]), np.full(ok.sum(), 0.2)])
    colors = np.tile(np.array([[150, 150, 150]], np.uint8), (len(pts), 1))
    track = np.array([row.get("track_x", np.nan), row.get("track_y", np.nan)], float)
    if np.isfinite(track).all():
        near = np.hypot(pts[:, 0] - track[0], pts[:, 1] - track[1]) <= _CLUSTER_RADIUS_M
        colors[near] = (230, 30, 30)
        rec.log("world/car/lidar/track", rr.Points3D([[track[0], track[1], 0.2]], radii=0.03, colors=[230, 30, 30],
                                                     labels=["LiDAR reference"]))
    else:
        rec.log("world/car/lidar/track", rr.Clear(recursive=False))
    rec.log("world/car/lidar", rr.Points3D(pts, radii=0.01, colors=colors))
