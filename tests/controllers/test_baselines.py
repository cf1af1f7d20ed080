"""The classical residual detectors (chi2, cusum): quiet on clean input, they catch a bias,
drive on the witness, answer ``would_pass`` as they then act, and use only the public contract."""

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from racf.controllers.baselines import Chi2Detector, CusumDetector
from racf.controllers.perception import PerceptionSample
from racf.plugins import ESTIMATORS

DETECTORS = [Chi2Detector, CusumDetector]
DT, SPEED = 0.02, 1.0


def _run(detector, depths, lidars):
    out, flags = [], []
    for d, l in zip(depths, lidars):
        out.append(detector.estimate(PerceptionSample(None, d, 1.0, l, 0.0), SPEED, DT))
        flags.append(detector.diagnostics()["flag"])
    return np.array(out), np.array(flags)


def _approach(n=120, seed=0, noise=0.03):
    rng = np.random.default_rng(seed)
    truth = 3.0 - SPEED * DT * np.arange(n)
    return truth, truth + rng.normal(0, noise, n), truth + rng.normal(0, noise, n)


@pytest.mark.parametrize("cls", DETECTORS)
def test_clean_depth_passes_unchanged_and_rarely_alarms(cls):
    flags = []
    for seed in range(20):
        det = cls()
        _, depth, lidar = _approach(seed=seed)
        out, flag = _run(det, depth, lidar)
        flags.append(flag)
        assert np.allclose(out[flag == 0], depth[flag == 0])
    assert np.mean(np.concatenate(flags)) < 0.02


@pytest.mark.parametrize("cls", DETECTORS)
def test_a_biased_depth_is_flagged_and_replaced_by_the_lidar(cls):
    det = cls()
    truth, depth, lidar = _approach()
    depth[60:] += 0.5
    out, flag = _run(det, depth, lidar)
    assert flag[:55].sum() == 0 and flag[70:].all()
    assert np.abs(out[70:] - truth[70:]).max() < 0.15  # the LiDAR, not the biased depth
    assert det.diagnostics()["score"] > 1.0


@pytest.mark.parametrize("cls", DETECTORS)
def test_without_any_witness_the_depth_is_all_there_is_and_odometry_carries_only_so_long(cls):
    det = cls(max_carry_s=0.1)
    out, flag = _run(det, [2.0, 1.98, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan],
                     [math.nan] * 8)
    assert out[0] == 2.0 and not flag.any()
    assert out[2] == pytest.approx(1.98 - SPEED * DT)  # carried by odometry
    assert math.isnan(out[-1])  # no guess after max_carry_s


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(DETECTORS), st.floats(-1.0, 1.0), st.integers(0, 40))
def test_would_pass_answers_what_the_next_step_does(cls, bias, steps):
    det = cls()
    truth, depth, lidar = _approach(n=steps + 1, seed=steps)
    _run(det, depth[:steps], lidar[:steps])
    next_depth = depth[steps] + bias
    expected_lidar = lidar[steps - 1] - SPEED * DT if steps else math.nan
    answer = det.would_pass(depth=next_depth, speed_mps=SPEED, dt=DT)
    _, flag = _run(det, [next_depth], [expected_lidar])
    assert answer == (flag[0] == 0.0)


def test_they_are_registered_as_plugins_and_import_only_the_public_contract():
    assert ESTIMATORS.plugin("chi2").obj is Chi2Detector and ESTIMATORS.plugin("cusum").obj is CusumDetector
    folder = Path(__file__).resolve().parents[2] / "controllers" / "baselines"
    for path in folder.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("racf"):
                assert node.module.startswith("racf.controllers.baselines"), (path.name, node.module)


@pytest.mark.parametrize("cls,bad", [(Chi2Detector, {"window": 0}), (Chi2Detector, {"false_alarm": 1.5}),
                                     (CusumDetector, {"h": 0}), (CusumDetector, {"recover_steps": 0})])
def test_bad_settings_fail_naming_what_is_allowed(cls, bad):
    with pytest.raises(ValueError, match="need"):
        cls(**bad)
