"""The supervisor of the car ahead: the defence's cap while its distance is vouched; the safe
controller's on the worst case otherwise, never bolder than the defence without positive evidence; a
stop once the car is faster than that worst case allows; easing off, never a hard brake, for what
appears from nowhere or what no LiDAR witness confirms. It reads only the published track."""

import math

import numpy as np
import pytest

from racf.experiments.car.stage import CarView, StageContext, TargetTrack
from racf.experiments.car.supervisor.envelope import Envelope, safe_speed
from racf.experiments.car.supervisor.vehicle import EASE_MPS2, VehicleSupervisor

NAN = math.nan
DT = 0.02
BUMPER = 0.1


class Advanced:
    """What the following stage publishes, as told: its witnesses, its distance and its cap."""

    def __init__(self) -> None:
        self.next = (NAN, NAN, NAN, math.inf)
        self.extra: dict = {}

    def track(self) -> TargetTrack:
        depth, lidar, fused, cap = self.next
        return TargetTrack("vehicle", fused, cap, moving=True, speed_mps=0.0, speed_known=False, depth_m=depth,
                           lidar_m=lidar, **self.extra)


def _stage() -> tuple[VehicleSupervisor, Advanced]:
    context = StageContext(None, (0.2, 0.0), 0.17, (0.1, 0.0), BUMPER, lambda: None, target_decel_mps2=6.0)
    # delta 0.1 m: round numbers to work by hand (the default budget is 0.12 + 0.05).
    stage = VehicleSupervisor(context, envelope=Envelope(witness_error_m=0.05, attack_error_m=0.05))
    stage.reset()
    return stage, Advanced()


def _view(speed: float, track: TargetTrack | None = None) -> CarView:
    return CarView({}, np.zeros(3), None, 0.0, speed, 0.0, 0.0, DT, True, False,
                   tracks={} if track is None else {"vehicle": track})


def _say(stage, advanced, speed, depth, lidar, fused, cap):
    advanced.next = (depth, lidar, fused, cap)
    return stage.step(_view(speed, advanced.track()))


def test_a_vouched_defence_drives_with_its_own_cap():
    stage, advanced = _stage()
    said = _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    assert said.values["sup_defence"] and said.speed_cap_mps == 0.7 and not said.values["sup_stop"]


def test_a_phantom_the_lidar_does_not_confirm_eases_the_car_off_never_a_hard_brake():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    # A phantom: the defence follows a picture at 0.5 m and stops the car; the range witnesses see the lead.
    said = _say(stage, advanced, 0.5, 1.5, 1.44, 0.5, 0.0)
    assert not said.values["sup_defence"] and said.values["sup_vouched"] and said.values["sup_eased"]
    # By hand: down from 0.5 m/s at 1.5 m/s^2 for one 0.02 s step.
    assert said.speed_cap_mps == pytest.approx(0.47)
    caps = [_say(stage, advanced, 0.5, 1.5, 1.44, 0.5, 0.0).speed_cap_mps for _ in range(3)]
    assert caps == pytest.approx([0.44, 0.41, 0.38])


def test_a_brake_the_lidar_confirms_is_never_eased():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    # The defence brakes for something at 0.6 m that the LiDAR's track sees too: its brake stands.
    said = _say(stage, advanced, 0.5, 1.5, 0.6, 0.6, 0.0)
    assert said.speed_cap_mps == 0.0 and not said.values["sup_eased"]


def test_holding_nothing_the_defence_s_cap_drives_whatever_it_is():
    stage, advanced = _stage()
    for _ in range(20):  # no range witness at all; the defence brakes to a stop on what it alone sees
        said = _say(stage, advanced, 1.0, NAN, NAN, 0.3, 0.0)
    assert not said.values["sup_carried"] and said.speed_cap_mps == 0.0 and not said.values["sup_eased"]


def test_a_car_faster_than_the_worst_case_gap_allows_is_told_to_stop_whatever_the_defence_says():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 0.5, 0.5, 0.5, 3.0)
    said = _say(stage, advanced, 2.0, 0.5, 0.5, 0.5, 3.0)
    assert said.values["sup_stop"] and said.speed_cap_mps == 0.0


def test_a_hidden_lead_is_carried_where_it_was_and_the_car_brought_to_rest_behind_it():
    stage, advanced = _stage()
    _say(stage, advanced, 0.8, 1.2, 1.2, 1.2, 0.8)
    speed, caps = 0.8, []
    for _ in range(300):  # 6 s with no witness at all; the defence has let go (no cap)
        said = _say(stage, advanced, speed, NAN, NAN, NAN, math.inf)
        caps.append(said.speed_cap_mps)
        speed = max(min(speed, said.speed_cap_mps), 0.0)
    assert said.values["sup_carried"] and not said.values["sup_vouched"]
    assert caps[-1] < 0.05 and said.values["sup_near"] - BUMPER > 0.0


def test_an_implausible_reading_eases_the_car_off_no_harder_than_ease():
    stage, advanced = _stage()
    _say(stage, advanced, 1.0, 2.0, 2.0, 2.0, 1.0)
    caps = [_say(stage, advanced, 1.0, 0.6, NAN, 0.6, 0.0).speed_cap_mps for _ in range(5)]
    assert caps[0] == pytest.approx(1.0 - EASE_MPS2 * DT) and np.allclose(np.diff(caps), -EASE_MPS2 * DT)


def test_nothing_seen_nothing_limited():
    stage, advanced = _stage()
    said = _say(stage, advanced, 1.0, NAN, NAN, NAN, math.inf)
    assert said.speed_cap_mps == math.inf and not said.values["sup_carried"] and not said.values["sup_stop"]
    assert set(said.values) >= {c.name for c in VehicleSupervisor.columns if c.name.startswith("sup_")}


def _scan_view(speed: float, scan, scan_new: bool = True) -> CarView:
    from types import SimpleNamespace

    s = np.arange(0.0, 6.0, 0.02)
    # A straight lane along x from the car at the origin; the camera 0.2 m ahead of the body origin.
    path = SimpleNamespace(points=np.column_stack([s, np.zeros_like(s)]), arclength=s)
    nothing = TargetTrack("vehicle", NAN, math.inf, moving=True, speed_known=False)  # no detection, no track
    return CarView({"lidar": scan}, np.zeros(3), path, 0.0, speed, 0.0, 0.0, DT, True, scan_new,
                   tracks={"vehicle": nothing})


def _car_scan(rear_from_camera: float) -> np.ndarray:
    """The LiDAR (0.1 m behind the camera, StageContext's) sees a car's rear this far ahead of the camera."""
    n = 720
    r = rear_from_camera + 0.1
    beams = np.arange(n) * 2 * math.pi / n
    scan = np.full(n, 9.0)
    scan[np.abs((beams + math.pi) % (2 * math.pi) - math.pi) <= math.atan2(0.096, r)] = r
    return scan


def test_the_lidar_s_lane_return_is_a_reading_carried_between_scans_by_the_closing_speed():
    stage, advanced = _stage()
    said = stage.step(_scan_view(0.5, _car_scan(1.2)))
    assert said.values["sup_vouched"] and -0.05 <= said.values["sup_on_lane"] - 1.2 <= 0.0
    first = said.values["sup_on_lane"]
    # No new scan: carried on by 0.5 m/s of closing (the lead's speed unknown: taken as 0) for 0.02 s.
    said = stage.step(_scan_view(0.5, _car_scan(1.2), scan_new=False))
    assert said.values["sup_on_lane"] == pytest.approx(first - 0.5 * DT)
    for _ in range(6):  # 0.14 s after the scan: still carried; after 0.15 s: too old
        said = stage.step(_scan_view(0.5, _car_scan(1.2), scan_new=False))
    assert math.isfinite(said.values["sup_on_lane"])
    said = stage.step(_scan_view(0.5, _car_scan(1.2), scan_new=False))
    assert math.isnan(said.values["sup_on_lane"])


def test_its_lidar_is_where_the_build_puts_it():
    # The LiDAR 0.25 m left of the camera: the car ahead of the camera lies to its right.
    context = StageContext(None, (0.2, 0.0), 0.17, (0.1, 0.25), BUMPER, lambda: None, target_decel_mps2=6.0)
    stage = VehicleSupervisor(context)
    stage.reset()
    n, r = 720, math.hypot(1.3, 0.25)
    beams = np.arange(n) * 2 * math.pi / n
    bearing = math.atan2(-0.25, 1.3)
    scan = np.full(n, 9.0)
    scan[np.abs((beams - bearing + math.pi) % (2 * math.pi) - math.pi) <= math.atan2(0.096, r)] = r
    said = stage.step(_scan_view(0.0, scan))
    assert -0.05 <= said.values["sup_on_lane"] - 1.2 <= 0.0


def test_before_its_first_step_it_says_nothing_and_limits_nothing():
    stage, _ = _stage()
    idle = stage.idle()
    assert idle.speed_cap_mps == math.inf and idle.values["sup_cap"] == math.inf
    assert all(idle.values[c.name] is False for c in VehicleSupervisor.columns
               if c.name.startswith("sup_") and c.unit == "bool")
    assert math.isnan(idle.values["sup_near"]) and math.isnan(idle.values["sup_reading"])


def test_a_lead_speed_confirmed_this_frame_bounds_the_carried_target():
    stage, advanced = _stage()
    # The following stage says the lead's speed is confirmed this frame (its track, or the broadcast).
    advanced.extra = {"speed_mps": 0.8}
    advanced.next = (1.0, 1.0, 1.0, 1.0)
    stage.step(_view(0.5, TargetTrack("vehicle", 1.0, 1.0, moving=True, speed_mps=0.8, speed_known=True,
                                      depth_m=1.0, lidar_m=1.0)))
    assert stage.carried.slow_mps == pytest.approx(0.55) and stage.carried.fast_mps == pytest.approx(1.05)


def test_the_safe_controller_follows_the_headway_policy_where_it_is_the_lower():
    stage, advanced = _stage()
    _say(stage, advanced, 0.3, 1.0, 1.0, 1.0, 1.0)
    # The defence off the reading: the safe controller. A fresh reading 1.0 m: 0.9 m of gap;
    # the headway policy allows (0.9 - 0.25) / 1 s = 0.65 m/s, the comfortable stop a little more.
    said = _say(stage, advanced, 0.3, 1.0, 1.0, 1.6, 2.0)  # the defence over-reads: it would go faster
    comfort = safe_speed(0.8, 0.0, stage.envelope, stage.envelope.comfort_brake_mps2)
    assert comfort > 0.65 and said.speed_cap_mps == pytest.approx(0.65)
    # Nothing vouched for a while, the carried worst case has the car stop behind it, never a negative cap.
    for _ in range(200):
        said = _say(stage, advanced, 0.0, NAN, NAN, NAN, math.inf)
    assert said.speed_cap_mps >= 0.0 and not said.values["sup_stop"]


# -- the car ahead's broadcast --------------------------------------------------------------------------


def _told(stage, advanced, depth, lidar, told_m, fused=None, speed=0.3, cap=1.0, follow=None, trusted=False):
    """A step on which the following stage passes on a broadcast witness at ``told_m`` (and followed
    ``follow``: by default the more cautious, as the following stage does)."""
    fused = depth if fused is None else fused
    if follow is None:
        follow = fused if not math.isfinite(fused) or abs(fused - told_m) <= 0.2 else min(fused, told_m)
    track = TargetTrack("vehicle", follow, cap, moving=True, speed_mps=0.0, speed_known=True, depth_m=depth,
                        lidar_m=lidar, broadcast_m=told_m, broadcast_mps=0.0, broadcast_trusted=trusted)
    return stage.step(_view(speed, track))


def test_a_reading_farther_than_the_broadcast_is_vouched_at_the_broadcast_and_said():
    stage, advanced = _stage()
    said = _told(stage, advanced, 2.0, 2.0, 1.0)  # the sensors spoofed away together; the lead says 1 m
    assert said.values["sup_broadcast"] and stage.carried.near_m == pytest.approx(1.0 - stage.envelope.delta_m)
    assert said.values["sup_defence"]  # the following stage followed the broadcast too: its cap drives
    stage, advanced = _stage()
    said = _told(stage, advanced, 2.0, 2.0, 1.0, follow=2.0)  # a following stage that ignored it
    assert said.values["sup_broadcast"] and not said.values["sup_defence"]  # not what was vouched: the safe one


def test_where_they_agree_or_the_sensors_are_nearer_the_sensors_reading_is_vouched():
    for depth, told in ((1.0, 1.1), (1.0, 2.0)):
        stage, advanced = _stage()
        said = _told(stage, advanced, depth, depth, told)
        assert not said.values["sup_broadcast"] and stage.carried.near_m == pytest.approx(depth - 0.1)
        assert said.values["sup_defence"]


def test_a_trusted_broadcast_alone_is_vouched_unless_it_puts_the_target_beyond_where_it_can_have_gone():
    stage, advanced = _stage()
    said = _told(stage, advanced, NAN, NAN, 1.2, trusted=True)  # the sensors see nothing (the lead hidden)
    assert said.values["sup_broadcast"] and stage.carried.near_m == pytest.approx(1.1)
    told = stage.carried.far_m  # as far as the bounds allow: vouched
    said = _told(stage, advanced, NAN, NAN, told, trusted=True)
    assert said.values["sup_broadcast"] and stage.carried.near_m == pytest.approx(told - 0.1)
    far, near = stage.carried.far_m, stage.carried.near_m
    said = _told(stage, advanced, NAN, NAN, far + 1.0, trusted=True)  # a lie past the carried bounds: nothing
    assert not said.values["sup_broadcast"] and stage.carried.far_m <= far + 0.1
    assert stage.carried.near_m < near  # carried on at the worst case


def test_an_untrusted_broadcast_alone_only_ever_makes_the_car_more_cautious():
    stage, advanced = _stage()
    _told(stage, advanced, 1.2, 1.2, 1.2)  # vouched by the sensors: near 1.1, far 1.3
    near = stage.carried.near_m
    said = _told(stage, advanced, NAN, NAN, near + 0.15)  # farther than the worst case, within the bounds
    assert not said.values["sup_broadcast"] and stage.carried.near_m < near  # ignored: carried at the worst
    said = _told(stage, advanced, NAN, NAN, 0.8)  # nearer than the worst case: taken
    assert said.values["sup_broadcast"] and stage.carried.near_m == pytest.approx(0.7)


def test_the_lead_s_speed_is_measured_from_its_range_rate_and_the_car_s_travel():
    # The car at 0.5 m/s; the lead's range grows 0.3 m/s from 1.0 m (its own stage says its speed is
    # unknown): after 20 steps (0.4 s, past the 0.3 s span) the lead is measured at 0.8 m/s.
    stage, advanced = _stage()
    for k in range(20):
        d = 1.0 + 0.3 * (k + 1) * DT
        said = _say(stage, advanced, 0.5, d, d, d, math.inf)
    assert said.values["sup_vouched"] and said.values["sup_lead_mps"] == pytest.approx(0.8)
    # A new chain (the readings jump 1 m: another target) measures again from its own readings: from
    # the step after the jump, the lead's speed is unmeasured.
    _say(stage, advanced, 0.5, 2.4, 2.4, 2.4, math.inf)
    said = _say(stage, advanced, 0.5, 2.4, 2.4, 2.4, math.inf)
    assert math.isnan(said.values["sup_lead_mps"])


def test_who_set_the_vouch_and_who_was_outvoted_is_said_each_step():
    """sup_broadcast: the broadcast set the vouched distance; sup_bc_outvoted: a broadcast was heard and not
    taken. Never both; neither without a broadcast."""
    stage, advanced = _stage()
    said = _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)  # no broadcast
    assert not said.values["sup_broadcast"] and not said.values["sup_bc_outvoted"] and not said.values["sup_eased"]
    said = _told(stage, advanced, 1.4, 1.4, 1.45)  # they agree: the sensors' reading, nothing outvoted
    assert not said.values["sup_broadcast"] and not said.values["sup_bc_outvoted"]
    stage, advanced = _stage()
    said = _told(stage, advanced, 1.4, 1.4, 2.4)  # the broadcast farther: outvoted by the sensors
    assert not said.values["sup_broadcast"] and said.values["sup_bc_outvoted"]
    stage, advanced = _stage()
    said = _told(stage, advanced, 2.4, 2.4, 1.4)  # the sensors farther: the broadcast's, nothing outvoted
    assert said.values["sup_broadcast"] and not said.values["sup_bc_outvoted"]
    fresh, advanced = _stage()
    said = _told(fresh, advanced, NAN, NAN, 1.2, trusted=True)  # the broadcast alone, nothing held
    assert said.values["sup_broadcast"] and not said.values["sup_bc_outvoted"]
    said = _told(fresh, advanced, NAN, NAN, fresh.carried.far_m + 1.0, trusted=True)  # past where it can be
    assert not said.values["sup_broadcast"] and said.values["sup_bc_outvoted"]
    nothing, advanced = _stage()
    said = _say(nothing, advanced, 1.0, NAN, NAN, NAN, math.inf)
    assert not said.values["sup_safe"] and not said.values["sup_defence"]  # nothing held: no safe controller


def test_a_first_sight_of_unknown_speed_may_be_anything_up_to_the_top_speed():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 1.5, 1.5, 1.5, 0.7)
    assert stage.carried.slow_mps == 0.0 and stage.carried.fast_mps == stage.envelope.target_max_mps == 3.0


def test_easing_off_ends_at_rest_never_below():
    stage, _ = _stage()
    stage._ease = 0.01  # 0.01 m/s left of an ease-off: one more step (0.03 m/s) ends it at rest, not below
    assert stage._eased(0.5, DT) == 0.0


def test_at_rest_close_behind_the_worst_case_the_cap_is_zero_never_negative():
    # Vouched at 0.3632 m: the near end 0.2632 m, the clear gap 0.1632 m. With b = 4 m/s^2 the car at rest
    # may stay (the stop rule allows 0.03 m/s), but the comfortable stop (1.5 m/s^2) allows no speed at all
    # (its formula gives 1.5 (-0.1 + sqrt(0.01 + 2 x 0.15 / 1.5)) - 0.736 = -0.199 m/s): the cap is 0.
    stage, advanced = _stage()
    said = _say(stage, advanced, 0.0, 0.3632, 0.3632, NAN, math.inf)
    assert not said.values["sup_stop"] and said.speed_cap_mps == 0.0
    assert safe_speed(0.1632, 0.0, stage.envelope, 1.5) == pytest.approx(-0.1986, abs=0.0005)


def test_the_headway_policy_divides_the_gap_by_its_time_headway():
    from racf.controllers.following import FollowingConfig

    context = StageContext(None, (0.2, 0.0), 0.17, (0.1, 0.0), BUMPER, lambda: None, target_decel_mps2=6.0)
    stage = VehicleSupervisor(context, envelope=Envelope(witness_error_m=0.05, attack_error_m=0.05),
                              policy=FollowingConfig(time_headway_s=2.0))
    stage.reset()
    advanced = Advanced()
    _say(stage, advanced, 0.3, 1.0, 1.0, 1.0, 1.0)
    said = _say(stage, advanced, 0.3, 1.0, 1.0, 1.6, 2.0)  # (0.9 - 0.25) / 2 s = 0.325 m/s
    assert said.speed_cap_mps == pytest.approx(0.325)


def test_between_scans_the_lane_return_moves_by_the_closing_speed_of_a_lead_of_known_speed():
    stage, _ = _stage()
    view = _scan_view(0.5, _car_scan(1.2))
    known = TargetTrack("vehicle", NAN, math.inf, moving=True, speed_mps=0.3, speed_known=True)
    said = stage.step(CarView(view.obs, view.pose, view.path, 0.0, 0.5, 0.0, 0.0, DT, True, True,
                              tracks={"vehicle": known}))
    first = said.values["sup_on_lane"]
    said = stage.step(CarView(view.obs, view.pose, view.path, 0.0, 0.5, 0.0, 0.0, DT, True, False,
                              tracks={"vehicle": known}))
    assert said.values["sup_on_lane"] == pytest.approx(first - (0.5 - 0.3) * DT)  # closing at 0.2 m/s


def test_the_lidar_is_placed_from_the_camera_across_too():
    # The camera 0.05 m right of the body's axis, the LiDAR 0.25 m left of it: 0.3 m left of the camera.
    context = StageContext(None, (0.2, -0.05), 0.17, (0.1, 0.25), BUMPER, lambda: None, target_decel_mps2=6.0)
    stage = VehicleSupervisor(context)
    assert stage._lidar_in_camera == pytest.approx((-0.1, 0.3))


def test_the_flags_of_a_vouched_defence_and_of_a_stop():
    stage, advanced = _stage()
    said = _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    assert said.values["sup_defence"] and not said.values["sup_safe"]
    fast = _say(stage, advanced, 3.0, 0.5, 0.5, NAN, math.inf)  # far too fast for 0.4 m: told to stop
    assert fast.values["sup_stop"] and fast.speed_cap_mps == 0.0 and not fast.values["sup_eased"]
    cautious, advanced = _stage()
    _told(cautious, advanced, 1.2, 1.2, 1.2)
    said = _told(cautious, advanced, NAN, NAN, 0.8)  # an untrusted broadcast nearer than the worst case: taken
    assert said.values["sup_broadcast"] and not said.values["sup_bc_outvoted"]


# -- the camera alone never brakes the car hard ---------------------------------------------------------


def _with_depth(speed: float, scan, depth: float, fused: float, cap: float, size: float = NAN) -> CarView:
    view = _scan_view(speed, scan)
    view.tracks["vehicle"] = TargetTrack("vehicle", fused, cap, moving=True, speed_known=False, depth_m=depth,
                                         size_m=size)
    return view


def test_a_depth_nearer_than_the_lane_the_lidar_sees_clear_is_no_reading():
    stage, _ = _stage()
    stage.step(_scan_view(0.5, _car_scan(1.2)))  # the lead vouched on the lane at about 1.2 m
    # A phantom picture: depth 0.8 m (and its box's size says 0.8 m), the lane return about 1.2 m.
    # 0.8 < 1.2 - 0.3 (LANE_SPREAD_M): left out, the lane return is the reading, vouched.
    said = stage.step(_with_depth(0.5, _car_scan(1.2), 0.8, 0.8, 0.3, size=0.8))
    assert said.values["sup_vouched"] and said.values["sup_reading"] == pytest.approx(said.values["sup_on_lane"])
    assert said.values["sup_reading"] > 1.1
    # 1.0 m is within 0.3 m of the lane return: a reading, the nearest, vouched at 1.0 m.
    stage2, _ = _stage()
    stage2.step(_scan_view(0.5, _car_scan(1.2)))
    said = stage2.step(_with_depth(0.5, _car_scan(1.2), 1.0, 1.0, 0.3))
    assert said.values["sup_reading"] == pytest.approx(1.0)


def test_a_defence_that_agrees_with_a_reading_no_lidar_witness_confirms_is_eased_not_obeyed():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    # The depth reads 1.3 m (within the carried bounds: vouched, the nearest); the defence agrees and brakes
    # to 0.2 m/s. The LiDAR's track reads 1.45 m, within agree_m(1.3) = 0.15 x 1.3 = 0.195 m: it confirms
    # the distance, so the defence's brake stands.
    said = _say(stage, advanced, 0.5, 1.3, 1.45, 1.3, 0.2)
    assert said.values["sup_defence"] and said.speed_cap_mps == 0.2 and not said.values["sup_eased"]
    # Now the LiDAR's track reads nothing: nothing confirms 1.3 m. Eased from 0.5 m/s: 0.5 - 1.5 x 0.02 = 0.47.
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 1.5, 1.45, 1.45, 0.7)
    said = _say(stage, advanced, 0.5, 1.3, NAN, 1.3, 0.2)
    assert said.values["sup_defence"] and said.values["sup_eased"]
    assert said.speed_cap_mps == pytest.approx(0.47)


def test_a_nearer_reading_only_the_camera_gives_lowers_the_cap_by_easing_and_once_a_step():
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 0.9, 0.9, 0.9, 0.7)  # vouched at 0.9 m: near end 0.8 m
    # The depth alone reads 0.8 m (no farther than the near end plus delta: vouched); gap 0.8 - 0.1 - 0.1 =
    # 0.6 m. By hand (rho 0.1 s, a 7.36 m/s^2, margin 0.05 m): the comfortable stop (1.5 m/s^2) allows
    # 1.5 (-0.1 + sqrt(0.01 + 2 x 0.5868 / 1.5)) - 0.736 = 0.449 m/s, the headway policy (0.7 - 0.25) / 1 =
    # 0.45 m/s, so 0.449 < 0.5; the stop rule (4 m/s^2) allows 1.07 m/s, so it does not fire.
    said = _say(stage, advanced, 0.5, 0.8, NAN, 2.0, 1.0)
    assert said.values["sup_vouched"] and not said.values["sup_stop"] and said.values["sup_eased"]
    assert said.speed_cap_mps == pytest.approx(0.47)  # eased once from 0.5 m/s (0.03 m/s), not twice
    # The LiDAR's track confirms 0.8 m: no easing; the safe controller's 0.449 m/s, reached at 2 m/s^2 at
    # most (FIRM_MPS2, never a hard brake of its own): 0.5 - 2 x 0.02 = 0.46 this step, then 0.449 below it.
    stage, advanced = _stage()
    _say(stage, advanced, 0.5, 0.9, 0.9, 0.9, 0.7)
    said = _say(stage, advanced, 0.5, 0.8, 0.8, 2.0, 1.0)
    assert not said.values["sup_eased"] and said.speed_cap_mps == pytest.approx(0.46)
    said = _say(stage, advanced, 0.5, 0.8, 0.8, 2.0, 1.0)  # from its last cap 0.46: 0.42 < 0.449, so 0.449
    assert said.speed_cap_mps == pytest.approx(0.449, abs=2e-3)


def test_a_lidar_track_on_something_beside_the_lane_is_no_reading_and_the_brake_for_it_is_eased():
    stage, _ = _stage()
    stage.step(_scan_view(0.5, _car_scan(1.2)))  # the lead vouched on the lane at about 1.2 m
    # The LiDAR's track latches on a wall at 0.6 m beside the lane; the defence follows it and stops the
    # car. The lane return (about 1.2 m) sees the lane clear to there: 0.6 < 1.2 - 0.3, so the track is
    # left out, the lane return vouched, and the defence's 0 eased: 0.5 - 1.5 x 0.02 = 0.47 m/s.
    view = _scan_view(0.5, _car_scan(1.2))
    view.tracks["vehicle"] = TargetTrack("vehicle", 0.6, 0.0, moving=True, speed_known=False, lidar_m=0.6)
    said = stage.step(view)
    assert said.values["sup_vouched"] and said.values["sup_reading"] > 1.1 and said.values["sup_eased"]
    assert said.speed_cap_mps == pytest.approx(0.47)
    assert not said.values["sup_stop"]


class _Route:
    """A route as the map gives it (points and their arclengths): 0.8 m straight ahead, then 45 degrees left."""

    def __init__(self) -> None:
        straight = [(x, 0.0) for x in np.arange(0.0, 0.8, 0.01)]
        bend = [(0.8 + u, u) for u in np.arange(0.0, 1.5, 0.01)]
        self.points = np.array(straight + bend)
        self.arclength = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(self.points, axis=0).T))])


def test_a_reading_along_the_camera_s_axis_is_vouched_at_the_lane_point_s_straight_line():
    stage, advanced = _stage()  # the camera 0.2 m ahead of the car's origin, the car at the route's start
    advanced.next = (0.8, NAN, 0.8, math.inf)  # the depth reads the lead 0.8 m along the axis
    view = CarView({}, np.zeros(3), _Route(), 0.0, 0.5, 0.0, 0.0, DT, True, False,
                   tracks={"vehicle": advanced.track()})
    said = stage.step(view)
    # 0.8 m ahead of the camera is x = 1.0 on the route, 0.2 m past the bend's start, so y = 0.2: in the
    # camera's frame (0.8, 0.2), a straight line of sqrt(0.64 + 0.04) m, what the chain vouches for.
    assert said.values["sup_vouched"] and said.values["sup_reading"] == pytest.approx(math.hypot(0.8, 0.2), abs=0.005)
    # With no route, the reading itself.
    plain, advanced = _stage()
    advanced.next = (0.8, NAN, 0.8, math.inf)
    assert plain.step(_view(0.5, advanced.track())).values["sup_reading"] == pytest.approx(0.8)
