"""Offline methods: causality (changing the future leaves the past alone), windows, and the
neuralforecast forecasts against the library's own predict."""

import numpy as np
import pandas as pd
import pytest

from racf.experiments.offline.forecasters import (NF_MODELS, ChronosForecaster, NFForecaster, NFSettings, _build,
                                             context_windows, train_nf, training_frame)
from racf.controllers import EKFEstimator, RawDepthEstimator
from racf.experiments.car.estimators import ODCAEstimator
from racf.experiments.offline.methods import (estimator_estimate, forecast_at, lidar_estimate, raw_estimate,
                                              split_arrays)
from racf.odca import LastValuePrior, ODCA
from racf.odca.align import Alignment

CUT = 150


def _frame(seed: int = 0, n: int = 240) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    parts = []
    for k in range(2):
        d = np.linspace(3.0, 0.6, n) + rng.normal(0, 0.01, n)
        d_meas = d.copy()
        d_meas[40:70] += 0.6  # a bias segment
        d_meas[100:120] = np.nan  # a blackout
        lidar = d + rng.normal(0, 0.01, n)
        lidar[::7] = np.nan
        parts.append(pd.DataFrame({"series_id": f"s{k}", "t": np.arange(n) * 0.02, "d_meas": d_meas,
                                   "c_meas": np.where(np.isfinite(d_meas), 0.9, 0.0), "lidar": lidar,
                                   "speed": np.full(n, 2.4 / (n * 0.02)), "label": np.zeros(n, int),
                                   "d_clean": d, "c_clean": np.full(n, 0.9), "d_true": d}))
    return pd.concat(parts, ignore_index=True)


def _future_changed(frame: pd.DataFrame) -> pd.DataFrame:
    """Every input after step CUT of the second series (and all of the later steps) rewritten."""
    out = frame.copy()
    later = np.arange(len(frame)) >= len(frame) // 2 + CUT
    rng = np.random.default_rng(7)
    for col in ("d_meas", "lidar"):
        out.loc[later, col] = rng.uniform(0.2, 5.0, later.sum())
    out.loc[later, "speed"] = 0.0
    return out


@pytest.fixture(scope="module")
def nf_models():
    train = training_frame(_frame(seed=3))
    settings = NFSettings(max_steps=3, windows_batch_size=32)
    return {name: train_nf(name, train, settings) for name in NF_MODELS}


def _estimates(frame: pd.DataFrame, nf_models: dict) -> dict[str, np.ndarray]:
    a = split_arrays(frame, Alignment(1.0, 0.0))
    out = {"raw": raw_estimate(a), "lidar": lidar_estimate(a), "ekf": estimator_estimate(EKFEstimator(), a),
           "odca": ODCA.load(prior=LastValuePrior()).run(frame)["d_fused"].to_numpy()}
    origins = np.flatnonzero(a.scored)
    for name, f in {"chronos": ChronosForecaster(), **nf_models}.items():
        est = np.full(len(a), np.nan)
        est[origins], _ = forecast_at(f, a, origins, 64, 16)
        out[name] = est
    return out


def test_every_method_is_causal(nf_models):
    frame = _frame()
    before, after = _estimates(frame, nf_models), _estimates(_future_changed(frame), nf_models)
    past = np.arange(len(frame)) < len(frame) // 2 + CUT
    future = ~past
    for name in before:
        np.testing.assert_array_equal(before[name][past], after[name][past], err_msg=name)
        if name != "raw":  # raw holds its input: it must see the change too
            assert not np.allclose(before[name][future], after[name][future], equal_nan=True), name


def test_context_windows_pad_inside_their_series_and_mask_gaps():
    values = np.array([np.nan, 1.0, 2.0, np.nan, 4.0, 5.0, 10.0, 11.0])
    first = np.array([1, 0, 0, 0, 0, 0, 1, 0], bool)
    windows, mask = context_windows(values, first, np.array([3, 5, 7, 1, 6]), width=4)
    np.testing.assert_array_equal(windows[0], [1.0, 1.0, 1.0, 2.0])  # steps 1, 2 with left padding
    np.testing.assert_array_equal(mask[0], [0, 0, 1, 1])
    np.testing.assert_array_equal(windows[1], [1.0, 2.0, 2.0, 4.0])  # step 3 holds 2.0, unmeasured
    np.testing.assert_array_equal(mask[1], [1, 1, 0, 1])
    np.testing.assert_array_equal(windows[2], [10.0] * 4)  # the next series does not see the first
    np.testing.assert_array_equal(mask[2], [0, 0, 0, 1])
    assert np.isnan(windows[3]).all() and np.isnan(windows[4]).all()  # no past: before step 1, a series' start


def test_batched_forecasts_equal_neuralforecast_predict():
    from neuralforecast import NeuralForecast

    frame = _frame(seed=5)
    train = training_frame(frame)
    settings = NFSettings(max_steps=3, windows_batch_size=32)
    a = split_arrays(frame.assign(label=0), Alignment())
    windows, mask = context_windows(a.d, a.first, np.array([80, 130, 200, 300, 450]), 64)
    for name in NF_MODELS:
        model = _build(name, settings)
        nf = NeuralForecast(models=[model], freq=1)
        nf.fit(train.assign(unique_id="all", ds=np.arange(len(train))) if name == "softs" else train)
        ours = NFForecaster(name, nf.models[0], settings, "test").forecast(windows, mask)
        column = type(model).__name__
        if name == "softs":  # multivariate: one window per call, or the windows would pool
            ref = np.stack([nf.predict(df=pd.DataFrame({"unique_id": "w", "ds": np.arange(64), "y": w,
                                                        "available_mask": m}))[column].to_numpy()
                            for w, m in zip(windows, mask)])
        else:
            df = pd.DataFrame({"unique_id": np.repeat(np.arange(len(windows)), 64),
                               "ds": np.tile(np.arange(64), len(windows)), "y": windows.ravel(),
                               "available_mask": mask.ravel()})
            ref = nf.predict(df=df)[column].to_numpy().reshape(len(windows), -1)
        np.testing.assert_allclose(ours, ref, atol=1e-5, err_msg=name)


def test_trained_baselines_are_cached_by_what_made_them(tmp_path):
    train = training_frame(_frame(seed=1))
    settings = NFSettings(max_steps=2, windows_batch_size=16)
    fresh = train_nf("nlinear", train, settings, tmp_path)
    again = train_nf("nlinear", train, settings, tmp_path)
    assert fresh.train_s is not None and again.train_s is None and again.key == fresh.key
    w = np.linspace(2.0, 1.0, 64)[None]
    np.testing.assert_array_equal(fresh.forecast(w), again.forecast(w))
    untrained = NFForecaster("nlinear", _build("nlinear", settings), settings, "untrained")
    assert not np.allclose(untrained.forecast(w), fresh.forecast(w))  # the trained weights are the ones kept
    other = train_nf("nlinear", train, NFSettings(max_steps=3, windows_batch_size=16), tmp_path)
    assert other.key != fresh.key and other.train_s is not None
    with pytest.raises(ValueError, match="model must be one of"):
        train_nf("arima", train, settings)
    with pytest.raises(ValueError, match="max_steps"):
        NFSettings(max_steps=0)


class _StepOnly:
    """An estimator without a batched path: the benchmark must step it."""

    def __init__(self, inner) -> None:
        self.inner = inner

    def reset(self) -> None:
        self.inner.reset()

    def estimate(self, *args):
        return self.inner.estimate(*args)


def test_an_estimator_run_step_by_step_gives_its_batched_numbers_and_raw_is_held_depth():
    frame = _frame(3)
    a = split_arrays(frame, Alignment(1.0, 0.0))
    odca = ODCAEstimator.of(ODCA.load(prior=LastValuePrior()))
    np.testing.assert_allclose(estimator_estimate(_StepOnly(odca), a), estimator_estimate(odca, a, frame),
                               rtol=0, atol=1e-9, equal_nan=True)
    np.testing.assert_array_equal(estimator_estimate(RawDepthEstimator(), a), raw_estimate(a))
