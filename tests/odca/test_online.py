"""The online module: Proposition 1 end to end, no NaN/inf out, clear errors, step == run."""

import json
import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odca import ODCA, Alignment, CheckpointError, GateConfig, LastValuePrior, ODCAConfig
from odca.features import MAX_RANGE_M
from odca.head import head_parameters, make_head
from odca.online import SHIPPED_HEAD


def _stub(alignment=Alignment(1.0, 0.0)) -> ODCA:
    """ODCA with the shipped head and a cheap stub prior (the Protocol makes it swappable)."""
    shipped = ODCA.load(prior=LastValuePrior())
    config = ODCAConfig.from_json({**shipped.config.to_json(), "alignment": {"alpha": alignment.alpha,
                                                                             "beta": alignment.beta}})
    return ODCA(config, shipped.head, LastValuePrior())


wild = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.just(0.0), st.floats(-5, 0),
                 st.floats(0.1, 5))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(wild, wild, wild, wild), min_size=1, max_size=40))
def test_no_nan_or_inf_out_for_any_input_sequence(rows):
    m = _stub()
    for depth, conf, lidar, speed in rows:
        out = m.step(depth=depth, confidence=conf, lidar=lidar, speed=speed)
        assert math.isfinite(out.d_fused) and math.isfinite(out.d_rep) and math.isfinite(out.r_delta)
        assert 0.0 <= out.d_fused <= MAX_RANGE_M and 0.0 <= out.d_rep <= MAX_RANGE_M
        assert 0.0 <= out.w <= 1.0


class _BlownUpPrior(LastValuePrior):
    """Forecasts no distance can have (as the tiny prior did on one test drive)."""

    def forecast(self, context, horizon):
        mean, std = super().forecast(context, horizon)
        return np.where(np.isfinite(mean), -15.0, mean), np.where(np.isfinite(std), 25.0, std)


class _NoPrior(LastValuePrior):
    def forecast(self, context, horizon):
        mean, std = super().forecast(context, horizon)
        return np.full_like(mean, np.nan), np.full_like(std, np.nan)


def test_a_forecast_that_is_no_distance_counts_as_no_forecast():
    shipped = _stub()
    blown, none = (ODCA(shipped.config, shipped.head, prior) for prior in (_BlownUpPrior(), _NoPrior()))
    frame = pd.DataFrame({"d_meas": [2.0 - 0.02 * t if t < 40 else np.nan for t in range(60)],
                          "c_meas": [0.9 if t < 40 else 0.0 for t in range(60)],
                          "lidar": [2.0 - 0.02 * t for t in range(60)], "speed": 1.0})
    pd.testing.assert_frame_equal(blown.run(frame), none.run(frame))
    # In the blackout the repair follows the LiDAR instead of the broken forecast.
    repaired = blown.run(frame)["d_fused"].to_numpy()[40:]
    assert np.abs(repaired - frame["lidar"].to_numpy()[40:]).max() < 0.3


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.2, 5), st.floats(-0.05, 0.05)), min_size=1, max_size=30))
def test_agreeing_sensors_pass_the_depth_through_exactly(rows):
    m = _stub()
    for depth, offset in rows:
        lidar = depth + offset * m.config.gate.tau_low / 0.05 * 0.999  # |r_XS| <= tau_low
        out = m.step(depth=depth, confidence=0.9, lidar=lidar, speed=1.0)
        assert out.w == 0.0 and out.d_fused == depth


def test_fused_is_a_convex_combination_and_missing_depth_is_repaired():
    m = _stub()
    for t in range(30):
        m.step(depth=2.0 - 0.02 * t, confidence=0.9, lidar=2.0 - 0.02 * t, speed=1.0)
    out = m.step(depth=3.5, confidence=0.9, lidar=1.38, speed=1.0)  # depth biased far
    assert out.w == 1.0 and out.r_xs == pytest.approx(2.12)
    assert min(3.5, out.d_rep) - 1e-9 <= out.d_fused <= max(3.5, out.d_rep) + 1e-9
    out = m.step(depth=float("nan"), confidence=0.0, lidar=1.36, speed=1.0)
    assert out.w == 1.0 and math.isfinite(out.d_fused) and abs(out.d_fused - 1.36) < 0.5


def test_wrong_shapes_and_columns_are_clear_errors():
    m = _stub()
    with pytest.raises(ValueError, match="scalar per step"):
        m.step(depth=np.ones(3), confidence=1.0)
    with pytest.raises(ValueError, match="d_meas"):
        m.run(pd.DataFrame({"x": [1.0]}))
    with pytest.raises(ValueError, match="dt"):
        m.step(depth=1.0, confidence=1.0, dt=0.0)


def _series(n, seed):
    rng = np.random.default_rng(seed)
    d = np.linspace(2.5, 0.5, n) + rng.normal(0, 0.005, n)
    d[rng.random(n) < 0.1] = np.nan
    d[n // 2:n // 2 + 20] += 0.7
    return pd.DataFrame({"d_meas": d, "c_meas": rng.uniform(0.3, 1, n), "lidar": d + 0.12, "speed": 1.0})


def test_batched_run_matches_step_exactly_with_the_shipped_prior():
    m = ODCA.load()
    a, b = _series(90, 0), _series(70, 1)
    df = pd.concat([a.assign(series_id="a"), b.assign(series_id="b")], ignore_index=True)
    batched = m.run(df)
    for sid, part in (("a", a), ("b", b)):
        m.reset()
        stepped = pd.DataFrame([vars(m.step(depth=r.d_meas, confidence=r.c_meas, lidar=r.lidar, speed=r.speed))
                                for r in part.itertuples()])
        got = batched[df["series_id"] == sid].reset_index(drop=True)
        pd.testing.assert_frame_equal(got, stepped, check_exact=True)


def test_head_size_and_checkpoint_errors(tmp_path):
    assert head_parameters(make_head()) == 917  # the paper's head has 921
    m = ODCA.load(prior=LastValuePrior())
    assert m.head.n_parameters == 917
    with pytest.raises(CheckpointError, match="no ODCA checkpoint"):
        ODCA.load(tmp_path / "nothing")
    m.save(tmp_path / "ok")
    assert ODCA.load(tmp_path / "ok", prior=LastValuePrior()).config == m.config
    (tmp_path / "ok" / "head.npz").write_bytes(b"garbage")
    with pytest.raises(CheckpointError, match="corrupt"):
        ODCA.load(tmp_path / "ok", prior=LastValuePrior())
    m.save(tmp_path / "bad_cfg")
    (tmp_path / "bad_cfg" / "odca.json").write_text(json.dumps({"refresh_steps": 99}))
    with pytest.raises(CheckpointError, match="corrupt"):
        ODCA.load(tmp_path / "bad_cfg", prior=LastValuePrior())
    assert (SHIPPED_HEAD / "train_report.json").exists()


def test_calibrate_fits_the_alignment_from_paired_arrays():
    m = _stub()
    l = np.linspace(0.5, 3, 100)
    a = m.calibrate(1.02 * l - 0.1, l)
    assert a.alpha == pytest.approx(1.02, abs=1e-3) and m.config.alignment == a
    assert isinstance(m.config.gate, GateConfig)
