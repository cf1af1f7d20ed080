"""ODCA on a target that moves (issue 69): its drift baseline's spread grows with how uncertain the
target's speed is; a standing target (a sign, ``moving_std_mps`` None) keeps the gate as it was."""

import math

import pytest

from racf.odca import ODCA, LastValuePrior
from racf.odca.kinematics import KinematicBranch, KinematicsConfig


def _follow(model: ODCA, steps: int, distance: float = 1.0, closing: float = 0.0):
    out = None
    for _ in range(steps):
        out = model.step(depth=distance, confidence=0.9, lidar=distance, speed=closing, bearing=0.0, dt=0.02)
    return out


def test_the_baseline_spreads_with_the_target_speed_uncertainty():
    still, moving = (KinematicBranch(KinematicsConfig()) for _ in range(2))
    for branch in (still, moving):
        branch.anchor(1.0, 0.0, confirmed=True)
    still.predict(0.5, 0.0, 0.1)
    moving.predict(0.5, 0.0, 0.1, target_speed_std_mps=0.3)
    assert moving.base_std == pytest.approx(still.base_std + 0.03)
    assert moving.base_z == still.base_z


@pytest.mark.parametrize("moving", [None, 0.1])
def test_a_box_nearer_than_the_range_witnesses_vetoes_them_for_a_moving_target_too(moving):
    # A picture of a car (a phantom) and a depth patch that drew the LiDAR's track along give the gate
    # the same vote; the box keeps its veto, and the supervisor's reading chain tells them apart.
    model = ODCA.load(prior=LastValuePrior())
    model.follow_moving_target(moving)
    _follow(model, 30)
    out = model.step(depth=1.0, confidence=0.9, lidar=1.0, speed=0.0, bearing=0.0, dt=0.02, size=0.5, size_std=0.03)
    assert out.source_name == "size" and out.d_fused < 0.9


def test_an_unknown_lead_speed_gives_the_baseline_no_weight():
    spreads = {}
    for std in (0.0, 1.5):  # a speed known exactly; one known this poorly
        model = ODCA.load(prior=LastValuePrior())
        model.follow_moving_target(std)
        _follow(model, 12)
        spreads[std] = model._witnesses.branch.base_std
    assert spreads[0.0] < 0.05 and spreads[1.5] > 0.3


def test_a_bad_speed_uncertainty_is_refused():
    with pytest.raises(ValueError, match="speed_std_mps"):
        ODCA.load(prior=LastValuePrior()).follow_moving_target(-1.0)
