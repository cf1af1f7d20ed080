import math

import numpy as np
import pytest

from racf.controllers import StanleyConfig, StanleyController


def _straight_east(n: int = 200, length_m: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
    x = np.linspace(0.0, length_m, n)
    return np.column_stack([x, np.zeros(n)]), np.zeros(n)


def test_on_the_line_and_aligned_it_steers_straight():
    pts, hds = _straight_east()
    assert StanleyController(pts, hds).steer(1.0, 0.0, 0.0, 1.0) == pytest.approx(0.0, abs=1e-9)


def test_left_of_the_line_it_steers_right_and_vice_versa():
    pts, hds = _straight_east()
    assert StanleyController(pts, hds).steer(1.0, 0.1, 0.0, 1.0) < 0
    assert StanleyController(pts, hds).steer(1.0, -0.1, 0.0, 1.0) > 0


def test_heading_error_is_corrected_and_output_is_limited():
    pts, hds = _straight_east()
    assert StanleyController(pts, hds).steer(1.0, 0.0, -0.2, 1.0) == pytest.approx(0.2, abs=0.05)
    big = StanleyController(pts, hds).steer(1.0, -2.0, -1.5, 1.0)
    assert big == pytest.approx(math.radians(30.0))


def test_kinematic_bicycle_converges_to_the_line():
    pts, hds = _straight_east(1000, 10.0)
    ctrl = StanleyController(pts, hds)
    x, y, yaw, v, wheelbase, dt = 0.0, 0.25, 0.3, 1.0, 0.256, 0.02
    for _ in range(300):  # 6 s: the cross-track error decays with a ~1.3 s time constant
        delta = ctrl.steer(x, y, yaw, v)
        x += v * math.cos(yaw) * dt
        y += v * math.sin(yaw) * dt
        yaw += v / wheelbase * math.tan(delta) * dt
    assert abs(y) < 0.02 and abs(yaw) < 0.05


def test_bad_inputs_raise_value_error():
    with pytest.raises(ValueError, match="points"):
        StanleyController(np.zeros((3, 3)), np.zeros(3))
    with pytest.raises(ValueError, match="k must be"):
        StanleyConfig(k=0)
