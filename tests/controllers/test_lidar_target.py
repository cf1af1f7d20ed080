"""LidarTargetTracker on ray-cast synthetic scans and on the recorded simulator scans."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from racf.controllers.lidar_target import LidarTargetConfig, LidarTargetState, LidarTargetTracker

SCANS = Path(__file__).resolve().parents[1] / "data" / "lidar_scans.npz"
LIDAR = np.array([-0.012, 0.0])  # body frame, m
CAMERA = np.array([0.095, 0.032])
DT = 0.02  # 50 Hz control
SCAN_EVERY = 5  # 10 Hz LiDAR
N_BEAMS = 360


def _plate(centre, width, normal_deg=180.0):
    """Segment of a plate (the LiDAR's cut through a sign) facing ``normal_deg`` (world)."""
    t = math.radians(normal_deg) + math.pi / 2
    half = 0.5 * width * np.array([math.cos(t), math.sin(t)])
    c = np.asarray(centre, float)
    return [(c - half, c + half)]


def _box(near_face_centre, depth, width, yaw_deg=0.0):
    """Crate outline: near face (``width`` across) at ``near_face_centre`` facing -x rotated by yaw."""
    yaw = math.radians(yaw_deg)
    fwd, left = np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)])
    c = np.asarray(near_face_centre, float)
    corners = [c - left * width / 2, c + left * width / 2, c + left * width / 2 + fwd * depth,
               c - left * width / 2 + fwd * depth]
    return [(corners[i], corners[(i + 1) % 4]) for i in range(4)]


@dataclass
class World:
    """Static segments in the world frame and a car driving with constant speed and yaw rate."""

    segments: list = field(default_factory=list)
    pose: np.ndarray = field(default_factory=lambda: np.zeros(3))  # x, y, yaw of the body frame
    noise_rel: float = 0.0
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))

    def scan(self, segments=None) -> np.ndarray:
        segs = self.segments if segments is None else segments
        x, y, yaw = self.pose
        c, s = math.cos(yaw), math.sin(yaw)
        origin = np.array([x, y]) + np.array([[c, -s], [s, c]]) @ LIDAR
        ang = yaw + 2 * np.pi * np.arange(N_BEAMS) / N_BEAMS
        d = np.column_stack([np.cos(ang), np.sin(ang)])  # (N, 2)
        best = np.full(N_BEAMS, np.inf)
        for a, b in segs:
            e = b - a
            w = a - origin
            den = d[:, 0] * (-e[1]) - d[:, 1] * (-e[0])
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (w[0] * (-e[1]) - w[1] * (-e[0])) / den
                u = (d[:, 0] * w[1] - d[:, 1] * w[0]) / den
            hit = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
            best = np.where(hit & (t < best), t, best)
        if self.noise_rel:
            best = best * (1 + self.noise_rel * self.rng.standard_normal(N_BEAMS))
        best[(best < 0.15) | (best > 12.0)] = np.inf
        return best.astype(np.float32)

    def to_camera(self, p_world) -> np.ndarray:
        x, y, yaw = self.pose
        c, s = math.cos(yaw), math.sin(yaw)
        body = np.array([[c, s], [-s, c]]) @ (np.asarray(p_world, float) - [x, y])
        return body - CAMERA

    def detection(self, centre, width=0.10):
        """Centre bearing and (left, right) box bearings of a target of ``width`` at ``centre``."""
        p = self.to_camera(centre)
        b = math.atan2(p[1], p[0])
        half = math.atan2(width / 2, float(np.hypot(*p)))
        return b, (b + half, b - half)

    def drive(self, speed: float, yaw_rate: float, dt: float = DT) -> None:
        x, y, yaw = self.pose
        h = yaw + yaw_rate * dt / 2
        self.pose = np.array([x + speed * dt * math.cos(h), y + speed * dt * math.sin(h), yaw + yaw_rate * dt])


def _run(world: World, tracker: LidarTargetTracker, centre, steps: int, *, speed=1.0, yaw_rate=0.0,
         detect=lambda k: True, scan_ok=lambda k: True, target="sign", start=0, segments=None, det_width=0.10,
         scan_age=0.0, beam_age_s=None):
    """Drives control steps ``start .. start + steps - 1`` (the car stands on step 0; a scan
    every 5th step, all-inf where ``scan_ok`` is false; the detection where ``detect``).
    Each scan is taken ``scan_age`` s before its step (see :func:`_scan_taken`), and
    ``beam_age_s`` is what the tracker is told.

    Returns:
        (values, truths, states) per step; truth = the target centre's optical-axis depth.
    """
    values, truths, states = [], [], []
    for k in range(start, start + steps):
        if k > 0:
            world.drive(speed, yaw_rate)
        scan = None
        if k % SCAN_EVERY == 0 and scan_ok(k):
            scan = _scan_taken(world, segments(k) if segments else None, scan_age,
                               speed if k > 0 else 0.0, yaw_rate if k > 0 else 0.0)
        elif k % SCAN_EVERY == 0:
            scan = np.full(N_BEAMS, np.inf, np.float32)
        bearing, span = world.detection(centre, det_width) if detect(k) else (math.nan, None)
        values.append(tracker.step(scan=scan, detection_bearing=bearing, detection_span=span, target=target,
                                   speed=speed if k > 0 else 0.0, yaw_rate=yaw_rate if k > 0 else 0.0, dt=DT,
                                   beam_age_s=beam_age_s))
        truths.append(world.to_camera(centre)[0])
        states.append(tracker.state)
    return np.array(values), np.array(truths), states


def _scan_taken(world: World, segments, age, speed: float, yaw_rate: float) -> np.ndarray:
    """A scan whose beams were taken ``age`` s ago (a float, or (N,) per beam: a sweeping
    LiDAR), the car on its arc at ``speed`` and ``yaw_rate`` back then."""
    now = world.pose
    ages = np.broadcast_to(np.asarray(age, float), (N_BEAMS,))
    scan = np.empty(N_BEAMS, np.float32)
    for a in np.unique(ages):
        world.pose = now
        world.drive(speed, yaw_rate, -a)  # back along the arc
        beams = ages == a
        scan[beams] = world.scan(segments)[beams]
    world.pose = now
    return scan


SIGN = np.array([2.5, -0.35])  # world frame, m (ahead and to the right)


def test_sign_alone_is_within_a_centimetre():
    world = World(_plate(SIGN, 0.07))
    values, truths, states = _run(world, LidarTargetTracker(), SIGN, 60)
    assert np.isfinite(values).all()
    np.testing.assert_allclose(values, truths, atol=0.01)
    s = states[-1]
    assert isinstance(s, LidarTargetState) and s.has_track and s.supported and s.target == "sign"
    assert s.position[0] == pytest.approx(values[-1]) and s.position[1] == pytest.approx(world.to_camera(SIGN)[1], abs=0.01)
    assert s.n_points >= 2 and 0.0 <= s.last_support_age_s < SCAN_EVERY * DT


def test_sign_with_range_noise_and_at_an_angle():
    # 1 % range noise and a plate turned 50 deg: far away one or two returns hit it, and a
    # return at the end of the cut lies up to 0.027 m off the centre's depth.
    sign = np.array([1.9, -0.3])
    world = World(_plate(sign, 0.07, normal_deg=130.0), noise_rel=0.01, rng=np.random.default_rng(2))
    values, truths, states = _run(world, LidarTargetTracker(), sign, 60)
    err = values - truths
    assert np.isfinite(err).all()
    assert np.sqrt(np.mean(err ** 2)) < 0.015 and np.max(np.abs(err)) < 0.04
    assert np.sqrt(np.mean(err[30:] ** 2)) < 0.01  # 3-4 returns once nearer than 1.4 m


def test_nearer_and_farther_objects_in_the_box_do_not_take_the_sign():
    sign_cam_bearing = World().detection(SIGN)[0]
    # A pole nearer than the sign at the box's left edge, and a wall 0.6 m behind the sign.
    near = 1.3 * np.array([math.cos(sign_cam_bearing + 0.012), math.sin(sign_cam_bearing + 0.012)]) + CAMERA
    clutter = _plate(near, 0.03) + _plate(SIGN + [0.6, 0.0], 1.5) + _plate(SIGN + [0.0, 0.7], 0.3)
    world = World(_plate(SIGN, 0.07) + clutter)
    values, truths, _ = _run(world, LidarTargetTracker(), SIGN, 40)
    assert np.isfinite(values).all()
    np.testing.assert_allclose(values, truths, atol=0.01)


def test_a_far_object_alone_in_the_box_is_not_taken_for_the_sign():
    # The sign gives no return (e.g. above the scan plane). A post right behind it at 2.2
    # times its distance fits the box's bearings but is too wide for the box at its depth
    # (the box would make it 0.22 m across); a wall behind that is too wide anyway.
    sign = np.array([1.5, -0.2])
    post = CAMERA + 2.2 * (sign - CAMERA)
    world = World(_plate(post, 0.04) + _plate(post + [0.4, 0.0], 1.5))
    values, _, states = _run(world, LidarTargetTracker(), sign, 20, speed=0.0)
    assert np.isnan(values).all() and not states[-1].has_track and states[-1].n_clusters >= 2


def test_dropped_scans_coast_on_odometry_then_nan_never_another_object():
    cfg = LidarTargetConfig()
    tracker = LidarTargetTracker(cfg)
    world = World(_plate(SIGN, 0.07) + _plate(SIGN + [0.0, 0.5], 0.07))  # a second sign 0.5 m to the left
    values, truths, _ = _run(world, tracker, SIGN, 11)
    np.testing.assert_allclose(values, truths, atol=0.01)
    # No scan for 15 steps (scan=None throughout: the LiDAR stalled), the car keeps driving.
    coast, truth, states = [], [], []
    for _ in range(15):
        world.drive(1.0, 0.0)
        coast.append(tracker.step(scan=None, detection_bearing=math.nan, detection_span=None, target="sign",
                                  speed=1.0, yaw_rate=0.0, dt=DT))
        truth.append(world.to_camera(SIGN)[0])
        states.append(tracker.state)
    coast, truth = np.array(coast), np.array(truth)
    age = np.array([s.last_support_age_s for s in states])
    fresh = age <= cfg.report_max_age_s
    assert fresh.any() and (~fresh).any()
    np.testing.assert_allclose(coast[fresh], truth[fresh], atol=0.01)  # carried by odometry
    assert np.isnan(coast[~fresh]).all() and all(s.has_track for s in states)
    # An empty scan, then scans with the sign gone and the other sign still there, with the
    # detection (now) on the other sign: nothing fits the track, so NaN, not the other sign.
    other = SIGN + [0.0, 0.5]
    values, _, states = _run(world, tracker, other, 30, start=26, scan_ok=lambda k: k > 30,
                             segments=lambda k: _plate(other, 0.07))
    assert np.isnan(values).all()
    assert states[-1].has_track and states[-1].gate_radius_m > cfg.gate_radius_m
    # Scans of the sign come back within drop_after_s: re-acquired.
    values, truths, _ = _run(world, tracker, SIGN, 10, start=56)
    assert np.isfinite(values[-5:]).all()
    np.testing.assert_allclose(values[-5:], truths[-5:], atol=0.01)


def test_lidar_alone_keeps_the_sign_through_a_second_without_detection():
    world = World(_plate(SIGN, 0.07) + _plate(SIGN + [0.7, 0.2], 1.0))
    values, truths, states = _run(world, LidarTargetTracker(), SIGN, 70, speed=1.0,
                                  detect=lambda k: k < 10)  # detection only for the first 0.2 s
    assert np.isfinite(values).all()
    np.testing.assert_allclose(values, truths, atol=0.01)
    assert truths[0] - truths[-1] > 1.3 and states[-1].supported


def test_turning_car_is_followed_by_odometry_between_scans():
    world = World(_plate(SIGN, 0.07))
    values, truths, _ = _run(world, LidarTargetTracker(LidarTargetConfig(smoothing=1.0)), SIGN, 50,
                             speed=1.0, yaw_rate=-0.3)
    np.testing.assert_allclose(values, truths, atol=0.01)


def test_track_is_dropped_after_drop_after_s_without_support():
    cfg = LidarTargetConfig(drop_after_s=0.5)
    tracker = LidarTargetTracker(cfg)
    world = World(_plate(SIGN, 0.07))
    _run(world, tracker, SIGN, 10, speed=0.0)
    assert tracker.state.has_track
    # The sign is not seen any more (scans hold nothing), no detection.
    _, _, states = _run(world, tracker, SIGN, 40, speed=0.0, detect=lambda k: False, start=10,
                        segments=lambda k: [])
    ages = np.array([s.last_support_age_s for s in states])
    kept = np.array([s.has_track for s in states])
    assert kept[ages <= 0.5].all() and not kept[-1]
    # Without a detection, a track never starts again, though the sign is back in the scans.
    values, _, states = _run(world, tracker, SIGN, 20, speed=0.0, detect=lambda k: False, start=50)
    assert np.isnan(values).all() and not states[-1].has_track


def test_no_detection_ever_gives_nan():
    world = World(_plate(SIGN, 0.07))
    values, _, states = _run(world, LidarTargetTracker(), SIGN, 30, detect=lambda k: False)
    assert np.isnan(values).all() and not states[-1].has_track
    assert math.isnan(states[-1].position[0]) and states[-1].n_clusters == 1


def test_crate_depth_is_its_near_face():
    crate = np.array([2.0, 0.05])
    for yaw in (0.0, 12.0):
        world = World(_box(crate, 0.12, 0.16, yaw_deg=yaw))
        values, truths, _ = _run(world, LidarTargetTracker(), crate, 40, target="obstacle", det_width=0.16)
        assert np.isfinite(values).all()
        np.testing.assert_allclose(values, truths, atol=0.015)


def test_a_sign_sized_cluster_is_not_a_crate_and_switching_target_drops_the_track():
    near_sign = np.array([1.1, -0.1])
    values, _, _ = _run(World(_plate(near_sign, 0.07)), LidarTargetTracker(), near_sign, 10, target="obstacle",
                        speed=0.0, det_width=0.16)
    assert np.isnan(values).all()
    world = World(_plate(SIGN, 0.07))
    tracker = LidarTargetTracker()
    _run(world, tracker, SIGN, 10)
    assert tracker.state.has_track
    tracker.step(scan=None, detection_bearing=math.nan, detection_span=None, target="obstacle", speed=0.0,
                 yaw_rate=0.0, dt=DT)
    assert not tracker.state.has_track
    tracker.reset()
    assert not tracker.state.has_track and math.isnan(tracker.state.depth)


@pytest.mark.parametrize("yaw_rate", [0.0, -0.4])
def test_old_beams_are_carried_forward_to_the_step(yaw_rate):
    # A sweeping LiDAR: every scan was taken 0.08 s before the step it is handed over on,
    # while the car drove at 1 m/s. Told the beams' age, the tracker is as good as with
    # fresh scans; not told, it is about 8 cm too far.
    age = 0.08
    cfg = LidarTargetConfig(smoothing=1.0)
    told, truths, _ = _run(World(_plate(SIGN, 0.07)), LidarTargetTracker(cfg), SIGN, 50, yaw_rate=yaw_rate,
                           scan_age=age, beam_age_s=age)
    assert np.isfinite(told).all()
    np.testing.assert_allclose(told, truths, atol=0.01)
    blind, _, _ = _run(World(_plate(SIGN, 0.07)), LidarTargetTracker(cfg), SIGN, 50, yaw_rate=yaw_rate,
                       scan_age=age)
    err = blind[5:] - truths[5:]
    assert np.isfinite(err[:10]).all() and np.all(np.isnan(err) | (err > 0.06))  # or it loses the sign


def test_a_scan_of_aged_beams_is_reported_speed_times_age_closer():
    # The same scans, told they are `age` old while the car drives straight at v: the
    # target was that much farther when the beams hit it.
    v, age = 1.0, 0.06
    cfg = LidarTargetConfig(smoothing=1.0)
    fresh, _, _ = _run(World(_plate(SIGN, 0.07)), LidarTargetTracker(cfg), SIGN, 40, speed=v, beam_age_s=0.0)
    aged, _, _ = _run(World(_plate(SIGN, 0.07)), LidarTargetTracker(cfg), SIGN, 40, speed=v,
                      beam_age_s=np.full(N_BEAMS, age))
    assert np.isfinite(fresh).all() and np.isfinite(aged).all()
    np.testing.assert_allclose(fresh[5:] - aged[5:], v * age, atol=1e-9)  # on and after the first moving scan


def test_a_sweeping_lidar_s_beams_each_keep_their_own_age():
    # One 0.1 s revolution counter-clockwise from the right (beam 270) ends on this step: the
    # sign ahead-right is seen ~0.075 s ago, a second sign ahead-left ~0.03 s ago. Each is
    # carried forward by its own beams' age.
    ages = 0.1 * (1.0 - ((np.arange(N_BEAMS) - 270) % N_BEAMS + 1) / N_BEAMS)
    left = np.array([2.2, 0.6])
    world = World(_plate(SIGN, 0.07) + _plate(left, 0.07))
    for centre in (SIGN, left):
        world.pose = np.zeros(3)
        values, truths, _ = _run(world, LidarTargetTracker(LidarTargetConfig(smoothing=1.0)), centre, 40,
                                 yaw_rate=-0.3, scan_age=ages, beam_age_s=ages)
        assert np.isfinite(values).all()
        np.testing.assert_allclose(values, truths, atol=0.01)


def test_beam_age_none_and_zero_are_the_same():
    world = World(_plate(SIGN, 0.07) + _plate(SIGN + [0.6, 0.0], 1.5), noise_rel=0.01)
    runs = []
    for beam_age_s in (None, 0.0, np.zeros(N_BEAMS)):
        world.pose, world.rng = np.zeros(3), np.random.default_rng(3)
        runs.append(_run(world, LidarTargetTracker(), SIGN, 40, yaw_rate=-0.2, beam_age_s=beam_age_s))
    assert np.isfinite(runs[0][0]).all()
    for values, _, states in runs[1:]:
        np.testing.assert_array_equal(values, runs[0][0])
        assert states == runs[0][2]


def test_recorded_simulator_scans_match_d_true():
    d = dict(np.load(SCANS))
    scan_of = {int(s): i for i, s in enumerate(d["scan_step"])}
    errors = []
    for episode in np.unique(d["episode"]):
        tracker = LidarTargetTracker()
        for t in np.flatnonzero(d["episode"] == episode):
            seen = np.isfinite(d["span_left"][t])
            value = tracker.step(scan=d["ranges"][scan_of[t]] if t in scan_of else None,
                                 detection_bearing=float(d["bearing"][t]) if seen else math.nan,
                                 detection_span=(float(d["span_left"][t]), float(d["span_right"][t])) if seen else None,
                                 target="sign" if d["target_is_sign"][t] else "obstacle",
                                 speed=float(d["speed"][t]), yaw_rate=float(d["yaw_rate"][t]), dt=DT)
            errors.append(value - d["d_true"][t])
    errors = np.array(errors)
    assert np.isfinite(errors).mean() > 0.9  # sign 1 is sometimes missed by every beam
    assert np.sqrt(np.nanmean(errors ** 2)) < 0.012 and np.nanmax(np.abs(errors)) < 0.03


@pytest.mark.parametrize("field, value", [
    ("eps_m", 0.0), ("max_range_m", 0.1), ("sector_half_angle_rad", 2.0), ("bearing_margin_rad", -0.1),
    ("sign_width_m", (0.2, 0.1)), ("obstacle_box_width_m", (0.1,)), ("gate_radius_m", 0.0),
    ("gate_growth_mps", -1.0), ("smoothing", 0.0), ("smoothing", 1.5), ("report_max_age_s", -0.1),
    ("drop_after_s", math.nan), ("camera_position_m", (0.1, 0.0, 0.2)), ("lidar_position_m", (5.0, 0.0)),
])
def test_bad_config_raises_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        LidarTargetConfig(**{field: value})


def test_bad_step_arguments_raise():
    tracker = LidarTargetTracker()
    kw = dict(detection_bearing=0.0, detection_span=None, speed=0.0, yaw_rate=0.0)
    with pytest.raises(ValueError, match="target"):
        tracker.step(scan=None, target="cone", dt=DT, **kw)
    with pytest.raises(ValueError, match="dt"):
        tracker.step(scan=None, target="sign", dt=-1.0, **kw)
    with pytest.raises(ValueError, match="scan"):
        tracker.step(scan=np.ones((2, 360)), target="sign", dt=DT, **kw)


@pytest.mark.parametrize("beam_age_s", [
    -0.01, math.nan, math.inf, True, "old", np.zeros(359), np.zeros((2, 360)), np.full(360, -1e-3),
    np.r_[np.zeros(359), np.nan],
])
def test_bad_beam_age_raises_naming_it(beam_age_s):
    tracker = LidarTargetTracker()
    with pytest.raises(ValueError, match="beam_age_s"):
        tracker.step(scan=np.full(360, 1.0), detection_bearing=0.0, detection_span=None, target="sign", speed=0.0,
                     yaw_rate=0.0, dt=DT, beam_age_s=beam_age_s)


def test_a_box_too_tall_for_a_return_s_depth_keeps_a_track_off_the_background():
    # The sign gives no return; a thin post 1.5 x as far stands inside its box. The box's
    # width at the post's depth still fits a sign (an oblique plate's box is narrow), but
    # its height (0.09 m at the sign) would make the sign 0.135 m tall there.
    sign = np.array([1.5, -0.2])
    post = CAMERA + 1.5 * (sign - CAMERA)
    world = World(_plate(post, 0.02))
    bearing, span = world.detection(sign, width=0.06)
    height = 0.09 / world.to_camera(sign)[0]  # the box's height per metre of depth
    args = dict(scan=world.scan(), detection_bearing=bearing, detection_span=span, target="sign", speed=0.0,
                yaw_rate=0.0, dt=DT)
    blind = LidarTargetTracker()
    assert blind.step(**args) == pytest.approx(world.to_camera(post)[0], abs=0.02)  # width alone lets it in
    assert not blind.depth_confirmed  # ... and says no depth ever agreed with it
    assert math.isnan(LidarTargetTracker().step(**args, detection_height=height))


def test_a_track_is_depth_confirmed_once_the_depth_agrees_with_it():
    world = World(_plate(SIGN, 0.07))
    bearing, span = world.detection(SIGN)
    depth = world.to_camera(SIGN)[0]
    tracker = LidarTargetTracker()
    args = dict(scan=world.scan(), detection_bearing=bearing, detection_span=span, target="sign", speed=0.0,
                yaw_rate=0.0, dt=DT)
    tracker.step(**args)  # started with no depth (blacked out)
    assert tracker.state.has_track and not tracker.depth_confirmed
    tracker.step(**args, detection_depth=depth + 0.5)  # a depth that disagrees confirms nothing
    assert not tracker.depth_confirmed
    tracker.step(**args, detection_depth=depth)
    assert tracker.depth_confirmed


def test_a_car_ahead_is_reported_at_its_rear_though_the_scan_plane_cuts_its_lidar_behind_it():
    rear = np.array([1.5, 0.03])
    behind = LidarTargetConfig().vehicle_scan_behind_m
    # The scan plane meets only the other car's RPLIDAR housing, 0.076 m across, behind its rear.
    world = World(_box(rear + [behind, 0.0], 0.076, 0.076))
    values, truths, states = _run(world, LidarTargetTracker(), rear, 40, target="vehicle", det_width=0.19)
    assert np.isfinite(values[5:]).all() and states[-1].target == "vehicle"
    np.testing.assert_allclose(values[5:], truths[5:], atol=0.02)
    sign_sized = _run(World(_box(rear, 0.076, 0.076)), LidarTargetTracker(), rear, 40, target="sign")[0]
    np.testing.assert_allclose(sign_sized[5:], _run(World(_box(rear, 0.076, 0.076)), LidarTargetTracker(), rear, 40,
                                                    target="vehicle")[0][5:] + behind, atol=0.02)
