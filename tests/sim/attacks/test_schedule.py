"""``AttackSchedule``: when an attack window opens, how long it lasts, and the cooldown after it."""

import numpy as np
import pytest

from racf.sim.attacks import AttackSchedule


def test_schedule_opens_after_a_stable_sighting_inside_the_braking_window():
    schedule = AttackSchedule(duration_s=0.1, cooldown_s=0.5, window_s=1.0, stable_steps=3, max_windows=2)
    seen, unseen = np.ones((8, 8), bool), np.zeros((8, 8), bool)

    def info(t, visible, dist, speed=1.0):
        return {"time": t, "sign_mask": seen if visible else unseen, "dist_to_stop_line": dist, "speed": speed}
    # Visible but far (2 s from the line): no attack.
    assert not any(schedule.update(info(0.02 * i, True, 2.0)) for i in range(10))
    # Inside the window but the sighting restarts: needs 3 consecutive visible steps.
    assert not schedule.update(info(0.20, False, 0.9))
    assert not schedule.update(info(0.22, True, 0.9))
    assert not schedule.update(info(0.24, True, 0.9))
    assert schedule.update(info(0.26, True, 0.9))
    assert schedule.windows == [(0.26, pytest.approx(0.36))]
    # Active for the drawn duration, then quiet through the cooldown.
    assert schedule.update(info(0.34, True, 0.8))
    assert not schedule.update(info(0.40, True, 0.8))
    assert not schedule.update(info(0.80, True, 0.5))
    assert schedule.update(info(0.90, True, 0.4))
