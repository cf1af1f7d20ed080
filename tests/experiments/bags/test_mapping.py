"""A recording's camera and LiDAR as its mapping declares them: the intrinsics follow the frames
through the crop and the resize (a point lands where the frames put it), the field of view stands
for square centred intrinsics, and a value that cannot be one is one line naming what is allowed."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.errors import UserError
from racf.experiments.bags.mapping import Mapping


def _project(k, point):
    fx, fy, cx, cy = k
    x, y, z = point
    return cx + fx * x / z, cy + fy * y / z


@settings(max_examples=200, deadline=None)
@given(fx=st.floats(200, 2000), fy=st.floats(200, 2000), cx=st.floats(300, 900), cy=st.floats(200, 500),
       crop=st.tuples(st.integers(0, 200), st.integers(0, 100), st.integers(900, 1280), st.integers(600, 720)),
       size=st.tuples(st.integers(80, 640), st.integers(60, 480)),
       point=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.5, 10)))
def test_a_point_lands_where_the_cropped_and_resized_frame_puts_it(fx, fy, cx, cy, crop, size, point):
    mapping = Mapping(camera_crop=crop, camera_size=size, camera_intrinsics=(fx, fy, cx, cy))
    u, v = _project((fx, fy, cx, cy), point)  # in the recorded 1280 x 720 frame
    x0, y0, x1, y1 = crop
    sx, sy = (x1 - x0) / size[0], (y1 - y0) / size[1]
    expected = ((u - x0 + 0.5) / sx - 0.5, (v - y0 + 0.5) / sy - 0.5)  # OpenCV's resize of pixel centres
    got = _project(mapping.car_intrinsics(1280, 720, size), point)
    assert got == pytest.approx(expected, abs=1e-6)


def test_the_field_of_view_is_square_centred_intrinsics_and_nothing_declared_is_racf_s_model():
    by_fov = Mapping(camera_hfov_deg=90.0).car_intrinsics(1280, 720, (1280, 720))
    assert by_fov == pytest.approx((640.0, 640.0, 639.5, 359.5))
    assert Mapping().car_intrinsics(1280, 720, (320, 240)) is None


@pytest.mark.parametrize("raw, words", [
    ({"camera": {"intrinsics": [900, 900, 640]}}, "[camera] intrinsics must be [fx, fy, cx, cy]"),
    ({"camera": {"intrinsics": [0, 900, 640, 360]}}, "fx, fy > 0"),
    ({"camera": {"intrinsics": [900, 900, 640, 360], "hfov_deg": 69.4}}, "takes intrinsics or hfov_deg, not both"),
    ({"camera": {"hfov_deg": 180}}, "[camera] hfov_deg must be a number of degrees in [1, 179]"),
    ({"camera": {"hfov_deg": True}}, "[camera] hfov_deg must be"),
    ({"lidar": {"position_m": [0.1]}}, "[lidar] position_m must be [x, y]"),
    ({"lidar": {"position_m": [2.0, 0.0]}}, "each within 1 m"),
    ({"lidar": {"mount": 1}}, "[lidar] has no key 'mount'; it takes yaw_deg, position_m"),
])
def test_a_declaration_that_cannot_be_is_one_line_naming_what_is_allowed(raw, words):
    with pytest.raises(UserError) as err:
        Mapping.from_dict(raw, "my.toml")
    assert words in str(err.value) and str(err.value).startswith("mapping my.toml: ") and "\n" not in str(err.value)


def test_what_is_declared_is_read():
    m = Mapping.from_dict({"camera": {"intrinsics": [924, 924.5, 639.5, 359.5]}, "lidar": {"position_m": [0.1, -0.02]}})
    assert m.camera_intrinsics == (924.0, 924.5, 639.5, 359.5) and m.lidar_position_m == (0.1, -0.02)
    assert math.isclose(Mapping.from_dict({"camera": {"hfov_deg": 69}}).camera_hfov_deg, 69.0)
    assert np.isfinite(m.car_intrinsics(1280, 720, (320, 240))).all()


@pytest.mark.parametrize("raw, allowed", [
    ({"topics": {"rgb": "camera"}}, False), ({"topics": {"rgb": "/camera"}}, True),
    ({"camera": {"crop": [10, 0, 10, 720]}}, False), ({"camera": {"crop": [0, 10, 1280, 10]}}, False),
    ({"camera": {"crop": [-1, 0, 1280, 720]}}, False), ({"camera": {"crop": [0, 0, 1280, 720]}}, True),
    ({"camera": {"crop": [0, 0, 1280.0, 720]}}, False), ({"camera": {"crop": [0, 0, 1280]}}, False),
    ({"camera": {"size": [15, 240]}}, False), ({"camera": {"size": [16, 16]}}, True),
    ({"camera": {"size": [4096, 4096]}}, True), ({"camera": {"size": [4097, 240]}}, False),
    ({"camera": {"size": [320]}}, False),
    ({"camera": {"intrinsics": [900, 0, 640, 360]}}, False), ({"camera": {"intrinsics": [1, 1, 0, 0]}}, True),
    ({"camera": {"hfov_deg": 1}}, True), ({"camera": {"hfov_deg": 179}}, True), ({"camera": {"hfov_deg": 0.5}}, False),
    ({"lidar": {"position_m": [1.0, -1.0]}}, True), ({"lidar": {"position_m": [0.0, 1.01]}}, False),
    ({"lidar": {"quantum_m": 0.0}}, True), ({"lidar": {"quantum_m": 0.1}}, True), ({"lidar": {"quantum_m": 0.11}}, False),
    ({"lidar": {"quantum_m": -0.001}}, False),
    ({"lidar": {"read_per_rev": 1}}, True), ({"lidar": {"read_per_rev": 100_000}}, True),
    ({"lidar": {"read_per_rev": 0}}, False), ({"lidar": {"read_per_rev": 100_001}}, False),
    ({"lidar": {"read_per_rev": True}}, False), ({"lidar": {"yaw_deg": 90.5}}, False),
])
def test_each_value_s_edges_are_where_its_line_says(raw, allowed):
    if allowed:
        Mapping.from_dict(raw, "edge.toml")
    else:
        with pytest.raises(UserError, match="^mapping edge.toml: "):
            Mapping.from_dict(raw, "edge.toml")


def test_the_defaults_are_a_bag_racf_wrote():
    m = Mapping.from_dict({})
    assert (m.read_per_rev, m.lidar_yaw_deg, m.camera_crop, m.camera_intrinsics, m.lidar_position_m) == \
        (384, 180.0, None, None, None)


def test_a_field_of_view_other_than_a_right_angle_and_no_file_at_all():
    fx, fy, cx, cy = Mapping(camera_hfov_deg=60.0).car_intrinsics(1280, 720, (1280, 720))
    assert fx == fy == pytest.approx(640.0 / math.tan(math.radians(30.0))) and (cx, cy) == (639.5, 359.5)
    assert Mapping.load(None) == Mapping()
