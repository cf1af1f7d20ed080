"""One clear gap for the referee and the supervisor (racf.vehicle): the supervisor's, from its camera's
straight-line distance, is never more than the referee's gap from the poses."""

import math

from hypothesis import given
from hypothesis import strategies as st

from racf.vehicle import QCAR2_BOX_M, clear_gap_m, clear_gap_of_poses

BUMPER_X, CAMERA_X = 0.2125, 0.095


def test_behind_on_a_straight_it_is_the_bumper_to_rear_distance():
    # The lead's origin 1.0 m ahead of the ego's: 1.0 - 0.2125 - 0.2125 between bumper and rear.
    assert clear_gap_of_poses(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, BUMPER_X) == 1.0 - 0.425
    assert QCAR2_BOX_M[0] == 0.425
    # The camera reads 1.0 - 0.2125 - 0.095 = 0.6925 m to the rear; less the bumper's lead of 0.1175 m.
    assert math.isclose(clear_gap_m(0.6925, BUMPER_X - CAMERA_X), 0.575)


@given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-math.pi, math.pi), st.floats(-math.pi, math.pi))
def test_the_gap_from_the_camera_is_never_more_than_the_referee_s(lead_x, lead_y, ego_yaw, lead_yaw):
    gap = clear_gap_of_poses(0.0, 0.0, ego_yaw, lead_x, lead_y, lead_yaw, BUMPER_X)
    rear_x, rear_y = lead_x - 0.2125 * math.cos(lead_yaw), lead_y - 0.2125 * math.sin(lead_yaw)
    camera_x, camera_y = CAMERA_X * math.cos(ego_yaw), CAMERA_X * math.sin(ego_yaw)
    straight = math.hypot(rear_x - camera_x, rear_y - camera_y)
    assert clear_gap_m(straight, BUMPER_X - CAMERA_X) <= gap + 1e-9
    # The part along the axis is less again (never more than the straight line).
    axial = (rear_x - camera_x) * math.cos(ego_yaw) + (rear_y - camera_y) * math.sin(ego_yaw)
    assert axial <= straight + 1e-9


def test_a_lead_turned_a_quarter_has_its_rear_half_a_length_behind_its_origin_along_its_heading():
    # The lead at (0, 1) heading +y (yaw 90 degrees): its rear centre at (0, 1 - 0.2125). The ego at the
    # origin heading +y too: its bumper at (0, 0.2125). Gap 1 - 0.425 = 0.575 m.
    assert math.isclose(clear_gap_of_poses(0.0, 0.0, math.pi / 2, 0.0, 1.0, math.pi / 2, BUMPER_X), 0.575)
    # The lead heading -y (towards the ego): its rear is the far face, at (0, 1.2125).
    assert math.isclose(clear_gap_of_poses(0.0, 0.0, math.pi / 2, 0.0, 1.0, -math.pi / 2, BUMPER_X), 1.0)


def test_the_box_is_the_qcar2_s_stated_size():
    """0.425 x 0.192 x 0.20 m: the facts page of the car (shared/reference/qcar2.md), length x width x height."""
    import re
    from pathlib import Path

    facts = Path(__file__).resolve().parents[2] / "shared" / "reference" / "qcar2.md"
    if facts.exists():
        row = re.search(r"length x width x height \| ([\d.]+) x ([\d.]+) x ([\d.]+) m", facts.read_text())
        assert tuple(float(v) for v in row.groups()) == QCAR2_BOX_M
    assert QCAR2_BOX_M == (0.425, 0.192, 0.20)
