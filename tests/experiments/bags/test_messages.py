"""One reading <-> one ROS 2 message: what each round trip keeps, over many drawn values."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from racf.experiments.bags import messages as m
from racf.experiments.bags.topics import typestore
from racf.sim.sensors.a2m12 import driver_scan
from racf.sim.sensors.state import OdometryConfig


def _through_cdr(msg):
    """The message serialised as a bag stores it and read back."""
    store = typestore()
    return store.deserialize_cdr(store.serialize_cdr(msg, msg.__msgtype__), msg.__msgtype__)


@given(hnp.arrays(np.uint8, st.tuples(st.integers(1, 12), st.integers(1, 12), st.just(3))))
def test_colour_is_kept_to_the_bit(rgb):
    assert np.array_equal(m.rgb_from(_through_cdr(m.image_msg(rgb, 5))), rgb)


@given(hnp.arrays(np.int64, st.tuples(st.integers(1, 9), st.integers(1, 9)), elements=st.integers(0, 65535)))
def test_depth_in_the_d435s_millimetres_is_kept_to_the_bit(mm):
    # racf's depth camera quantises to the z16 unit: count x float32(0.001).
    depth = mm.astype(np.float32) * np.float32(0.001)
    assert np.array_equal(m.depth_from(_through_cdr(m.depth_msg(depth, 0))), depth)


@given(hnp.arrays(np.float32, (4, 5), elements=st.floats(0.0, 65.0, width=32)))
def test_any_depth_comes_back_within_half_a_millimetre(depth):
    """Half a millimetre of rounding, plus float32's own resolution at that depth (about 1e-7 x depth:
    the millimetres come back as count x float32(0.001))."""
    back = m.depth_from(_through_cdr(m.depth_msg(depth, 0)))
    assert np.all(np.abs(back.astype(np.float64) - depth) <= 0.0005 + 1.2e-7 * depth.astype(np.float64))


@given(st.lists(st.one_of(st.integers(0, 12000), st.just(-1)), min_size=8, max_size=64))
def test_scan_ranges_at_the_a2m12s_millimetre_are_kept_to_the_bit(counts):
    # The A2M12's ranges: whole millimetres as round(r / q) * q, 0 = no return, NaN = not read.
    q = 0.001
    ranges = np.array([np.nan if c < 0 else c * q for c in counts])
    ranges = np.where(np.isnan(ranges), np.nan, np.round(ranges / q) * q)
    back = m.scan_from(_through_cdr(m.scan_msg(ranges, 0, 10.0, 12.0)), q)
    assert np.array_equal(back, ranges, equal_nan=True)


@given(st.floats(-6.25, 6.25, width=32), st.floats(-30, 30, width=32),
       st.floats(-30, 30, width=32))
def test_the_fix_is_kept_to_the_bit_in_float32(yaw, x, y):
    pose = np.array([x, y, yaw], np.float32)
    assert np.array_equal(m.pose_from(_through_cdr(m.pose_msg(*pose, 0))), pose)


@given(st.integers(-20000, 20000))
def test_the_encoder_speed_is_kept_to_the_bit(counts_per_step):
    mpc = OdometryConfig().m_per_count
    speed = np.float32(counts_per_step * mpc * 50.0)
    msg = _through_cdr(m.joint_msg(0.0, float(speed) / mpc, 0))
    assert np.float32(float(msg.velocity[0]) * mpc) == speed


def test_a_scan_seen_from_the_virtual_cars_frame_gives_the_same_bins():
    """Quanser's virtual car mounts the LiDAR unturned (yaw 0): half a revolution later in the scan,
    the same bins once the mapping says so."""
    rng = np.random.default_rng(0)
    n = 1600
    ranges = np.round(rng.uniform(0.3, 5.0, n) / 0.001) * 0.001
    times = np.linspace(0.0, 0.1, n)
    physical = driver_scan(ranges, times, yaw_deg=180.0)
    virtual = driver_scan(np.roll(ranges, n // 2), np.roll(times, n // 2), yaw_deg=0.0)
    assert np.allclose(physical[0], virtual[0], rtol=0, atol=1e-6)
    assert np.allclose(physical[1], virtual[1], rtol=0, atol=1e-9)


def test_the_bytes_are_laid_out_as_quanser_and_ros_lay_them():
    """What a second reader of the bag sees, byte by byte: the reversal Quanser's driver writes (a
    return at sample i sits at ranges[N-1-i]) and depth as little-endian millimetres (1.234 m is 1234)."""
    ranges = np.zeros(16)
    ranges[3] = 1.5
    msg = m.scan_msg(ranges, 0, 10.0, 12.0)
    assert msg.ranges[16 - 1 - 3] == np.float32(1.5) and np.count_nonzero(msg.ranges) == 1
    assert m.scan_from(msg)[3] == 1.5
    depth = np.zeros((2, 3))
    depth[1, 2] = 1.234
    img = m.depth_msg(depth, 0)
    assert img.encoding == "mono16" and not img.is_bigendian and img.step == 6
    raw = np.asarray(img.data, np.uint8)
    assert int(raw[1 * 6 + 2 * 2]) | int(raw[1 * 6 + 2 * 2 + 1]) << 8 == 1234
    assert m.depth_from(img)[1, 2] == np.float32(1234) * np.float32(1.0 / 1000.0)
