"""The closed-loop estimators by name: each causal, each giving a distance from the live signals."""

import math

import numpy as np
import pytest

from racf.controllers import PerceptionSample
from racf.experiments.car.estimators import ESTIMATORS, make_estimator


def _samples(depths, lidar_offset=0.0):
    return [PerceptionSample(None, d, 0.9 if math.isfinite(d) else 0.0, d + lidar_offset, 0.0) for d in depths]


def _run(name, samples):
    est = make_estimator(name)
    est.reset()
    return np.array([est.estimate(s, 1.0, 0.02) for s in samples])


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow)  # 3-5 s each: the prior, or ODCA inside
                                  if n in ("chronos", "vote", "detectors_or", "odca") else n for n in ESTIMATORS])
def test_changing_the_future_does_not_change_the_past(name):
    rng = np.random.default_rng(0)
    depths = list(2.0 - 0.02 * np.arange(40) + rng.normal(0, 0.005, 40))
    cut = 23
    future = depths[:cut] + [math.nan] * 5 + [0.5] * (len(depths) - cut - 5)
    np.testing.assert_array_equal(_run(name, _samples(depths))[:cut], _run(name, _samples(future))[:cut])


@pytest.mark.parametrize("name", ["odca", "ekf"])
def test_repairing_estimators_bridge_a_missing_depth_with_the_lidar(name):
    depths = list(2.0 - 0.02 * np.arange(30))
    hidden = [PerceptionSample(None, math.nan, 0.0, d, 0.0) for d in depths[20:]]
    out = _run(name, _samples(depths[:20]) + hidden)
    assert np.isfinite(out[20:]).all()
    assert np.abs(out[20:] - np.array(depths[20:])).max() < 0.1


def test_raw_depth_has_nothing_without_a_detection_and_unknown_names_fail():
    out = _run("raw", _samples([1.0, math.nan]))
    assert out[0] == 1.0 and math.isnan(out[1])
    with pytest.raises(ValueError, match="unknown estimator 'kalman'; choose from"):
        make_estimator("kalman")


@pytest.mark.parametrize("name", ESTIMATORS)
def test_each_estimator_is_found_by_its_own_name_and_follows_the_protocol(name):
    from racf.controllers import DistanceEstimator

    est = make_estimator(name)
    assert est.name == name and isinstance(est, DistanceEstimator)
    est.reset()
    est.estimate(_samples([1.5])[0], 1.0, 0.02)
    diagnostics = est.diagnostics()
    assert all(isinstance(k, str) and isinstance(v, float) for k, v in diagnostics.items())


def test_odca_logs_its_gate_through_diagnostics():
    est = make_estimator("odca")
    est.reset()
    assert est.diagnostics() == {}
    est.estimate(_samples([1.5])[0], 1.0, 0.02, yaw_rate_radps=0.1)
    d = est.diagnostics()
    assert set(d) == {"w", "flag", "score", "odca_source", "d_kin"} and d["w"] in (0.0, 1.0)
    assert math.isnan(d["d_kin"])  # what the vote saw: no branch before the first depth
    est.estimate(_samples([1.48])[0], 1.0, 0.02)
    assert est.diagnostics()["d_kin"] == pytest.approx(1.5 - 1.0 * 0.02)  # the first depth, advanced


def test_a_trained_head_runs_by_option_and_its_content_enters_the_id(tmp_path):
    import json
    import shutil

    from racf.assets import asset_path
    from racf.experiments.episode import TrialSpec

    head = tmp_path / "odca-head"
    shutil.copytree(asset_path("checkpoints", "odca-head"), head)
    shipped = TrialSpec("attack+odca", 0, 1.0, 0)
    mine = TrialSpec("attack+odca", 0, 1.0, 0, estimator_options={"checkpoint": str(head)})
    assert make_estimator("odca", {"checkpoint": str(head)}).model.config == make_estimator("odca").model.config
    before = mine.trial_id
    assert before != shipped.trial_id
    config = json.loads((head / "odca.json").read_text())
    config["gate"]["tau_m"] = config["gate"]["tau_m"] + 0.01
    (head / "odca.json").write_text(json.dumps(config))
    assert mine.trial_id != before  # the same path, other weights or settings: another result
    with pytest.raises(ValueError, match="has no option\\(s\\) \\['flavour'\\]"):
        TrialSpec("attack+odca", 0, 1.0, 0, estimator_options={"flavour": 1})
