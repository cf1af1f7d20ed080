"""delta's first part is measured, not assumed: on clean following episodes the honest range witnesses
(the depth in the lead's box, the LiDAR's track of its rear) over-read the true clear-gap distance by no
more than the envelope's ``witness_error_m``; and so does the reading the supervisor vouches for, its
witnesses taken to the lane's straight line first (``along_lane``: never nearer than the axis)."""

import numpy as np
import pytest

from racf.experiments.car.supervisor.envelope import Envelope
from racf.experiments.episode import TrialSpec, run_trial
from racf.sim.sensors.calibration import car_build
from racf.vehicle import clear_gap_of_poses

pytestmark = pytest.mark.slow  # eight following episodes, about 40 s

PROFILES = [("cruise", 0), ("hard_brake", 1), ("stop_and_go", 2), ("slow_down", 3)]


def _episode(profile: str, seed: int, supervisor: bool):
    """The episode's log and the true camera distance to the lead's rear each step."""
    build = car_build(320, 240)
    beta = build.bumper_x_m - build.camera_xy_m[0]
    _, log = run_trial(TrialSpec("clean+odca", 1, 1.0, seed, target="lead_vehicle",
                                 scenario_params={"profile": profile}, supervisor=supervisor))
    truth = clear_gap_of_poses(*(log[c].to_numpy(float) for c in ("x", "y", "yaw", "lead_x", "lead_y", "lead_yaw")),
                               build.bumper_x_m) + beta
    return log, truth


@pytest.mark.parametrize("profile, seed", PROFILES)
def test_the_honest_witnesses_over_read_the_truth_by_no_more_than_witness_error(profile, seed):
    log, truth = _episode(profile, seed, supervisor=False)
    for witness in ("lead_d_meas", "lead_lidar"):
        over = log[witness].to_numpy(float) - truth
        over = over[np.isfinite(over)]
        assert over.size > 20, f"{witness} saw the lead too seldom to measure"
        assert over.max() <= Envelope().witness_error_m, f"{witness} over-read by {over.max():.3f} m"


@pytest.mark.parametrize("profile, seed", PROFILES)
def test_the_reading_the_supervisor_vouches_for_over_reads_by_no_more_than_witness_error(profile, seed):
    # The nearest witness, each taken to the lane's straight line: 0.093 m at most on these four (the
    # LiDAR's track alone reached 0.134 m on them, never as the nearest).
    log, truth = _episode(profile, seed, supervisor=True)
    vouched = log["sup_vouched"].to_numpy(bool)
    over = (log["sup_reading"].to_numpy(float) - truth)[vouched]
    assert vouched.sum() > 20, "the supervisor vouched too seldom to measure"
    assert over.max() <= Envelope().witness_error_m, f"the vouched reading over-read by {over.max():.3f} m"


@pytest.mark.parametrize("sign", range(4))
def test_the_car_s_route_distance_is_off_by_no_more_than_route_error(sign):
    # A6 measured: one approach per sign (the full measurement, 60 episodes, is route_error.py's: 0.069 m;
    # 0.080 m with a 0.075 m budget).
    from tests.experiments.car.supervisor.route_error import BASE_SEED, route_errors

    errors = route_errors(sign, 1.5, BASE_SEED + 1)
    assert errors.size > 20 and np.abs(errors).max() <= Envelope().route_error_m
