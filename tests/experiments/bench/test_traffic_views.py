"""The perception-under-traffic bench: each case puts its car where it says, and both maps run."""

import pytest

from racf.experiments.bench.traffic_views import CASES, _other_car, measure_case
from racf.experiments.cli import main
from racf.experiments.episode import TrialSpec, run_trial
from racf.sim.world.traffic_manager import TrafficManager


def test_the_between_car_hides_part_of_the_sign_when_it_says():
    case = CASES["between"]
    spec = TrialSpec("clean", case.sign, 1.0, 0, run_up_m=2.0)
    car = _other_car(case, spec)
    masks = {}

    def keep(name):
        def hook(env, obs, info, row):
            if abs(row["dist_to_stop_line"] - case.at_m) < 0.011:
                masks[name] = info["sign_mask"].sum()
        return hook

    from racf.experiments.bench.traffic_views import _WithCar
    from racf.experiments.episode.stack import default_env

    run_trial(spec, on_step=keep("empty"), clean_pass=False)
    run_trial(spec, make_env=lambda s: _WithCar(default_env(s, world=(TrafficManager(1),)), car), on_step=keep("traffic"),
              clean_pass=False)
    # The sign's visible face (ground truth) shrinks: the other car stands in the line of sight.
    assert masks["traffic"] < 0.7 * masks["empty"]


@pytest.mark.slow  # 1.4 s: the default run keeps under two minutes on 2 cores
def test_a_case_reports_both_maps_on_the_same_seeds():
    out = measure_case(CASES["red_car"], seeds=1)
    assert out["empty"]["n"] == out["traffic"]["n"] == 1
    for name in ("empty", "traffic"):
        assert set(out[name]) == {"n", "scr", "scr_ci", "collisions", "recall", "steps_in_view", "depth_off_share",
                                  "lidar_off_share"}
        assert 0.0 <= out[name]["recall"] <= 1.0


@pytest.mark.parametrize("argv, message", [(["--case", "nope"], "unknown case(s) ['nope']"),
                                           (["--estimator", "kalman"], "unknown estimator(s) ['kalman']"),
                                           (["--seeds", "0"], "--seeds must be >= 1")])
def test_bad_input_is_one_line_and_exit_2(capsys, argv, message):
    assert main(["bench-traffic", *argv]) == 2
    assert message in capsys.readouterr().err
