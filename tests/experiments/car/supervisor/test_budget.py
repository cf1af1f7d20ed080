"""delta's first part is measured, not assumed: on clean following episodes the honest range witnesses
(the depth in the lead's box, the LiDAR's track of its rear) over-read the true clear-gap distance by no
more than the envelope's ``witness_error_m``."""

import numpy as np
import pytest

from racf.experiments.car.supervisor.envelope import Envelope
from racf.experiments.episode import TrialSpec, run_trial
from racf.sim.sensors.calibration import car_build
from racf.vehicle import clear_gap_of_poses

pytestmark = pytest.mark.slow  # four following episodes, about 12 s


@pytest.mark.parametrize("profile, seed", [("cruise", 0), ("hard_brake", 1), ("stop_and_go", 2), ("slow_down", 3)])
def test_the_honest_witnesses_over_read_the_truth_by_no_more_than_witness_error(profile, seed):
    build = car_build(320, 240)
    beta = build.bumper_x_m - build.camera_xy_m[0]
    _, log = run_trial(TrialSpec("clean+odca", 1, 1.0, seed, target="lead_vehicle",
                                 scenario_params={"profile": profile}))
    truth = clear_gap_of_poses(*(log[c].to_numpy(float) for c in ("x", "y", "yaw", "lead_x", "lead_y", "lead_yaw")),
                               build.bumper_x_m) + beta
    for witness in ("lead_d_meas", "lead_lidar"):
        over = log[witness].to_numpy(float) - truth
        over = over[np.isfinite(over)]
        assert over.size > 20, f"{witness} saw the lead too seldom to measure"
        assert over.max() <= Envelope().witness_error_m, f"{witness} over-read by {over.max():.3f} m"
