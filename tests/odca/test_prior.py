"""The temporal prior: the shipped Chronos-2 checkpoint loads, forecasts and beats the naive forecast."""

import numpy as np
import pytest

from racf.odca import CheckpointError, Chronos2Prior, LastValuePrior
from racf.odca.pretrain import score_prior
from racf.odca.prior import SHIPPED_PRIOR
from racf.odca.synthetic import synthetic_series


@pytest.fixture(scope="module")
def prior():
    return Chronos2Prior()


def test_shipped_checkpoint_is_small_and_has_a_model_card():
    size = sum(p.stat().st_size for p in SHIPPED_PRIOR.iterdir())
    assert size < 5e6
    card = (SHIPPED_PRIOR / "MODEL_CARD.md").read_text()
    assert "**not** Amazon" in card and "ratio" in card


def test_forecast_shapes_quantile_std_and_missing_windows(prior):
    ctx = np.stack([np.linspace(3, 1, 64), np.full(64, np.nan), np.r_[np.full(40, np.nan), np.linspace(2, 1.5, 24)]])
    mean, std = prior.forecast(ctx, 16)
    assert mean.shape == std.shape == (3, 16)
    assert np.isfinite(mean[[0, 2]]).all() and (std[[0, 2]] >= 0).all()
    assert np.isnan(mean[1]).all()  # nothing to go on
    assert mean[0, -1] < mean[0, 0] + 0.05  # a falling approach keeps falling (or holds)
    with pytest.raises(ValueError, match=r"\(batch, window\)"):
        prior.forecast(np.zeros(64), 16)


def test_a_window_gets_the_same_numbers_alone_or_in_a_batch(prior):
    rng = np.random.default_rng(1)
    ctx = rng.normal(2, 0.2, (11, 64))
    alone = prior.forecast(ctx[7:8], 16)[0][0]
    together = prior.forecast(ctx, 16)[0][7]
    assert np.array_equal(alone, together)


def test_a_window_with_nothing_in_it_is_nan_without_running_the_model(prior, monkeypatch):
    # Before the first sight a window is all NaN: its answer is NaN, and the model is not asked.
    monkeypatch.setattr(prior, "_forward", lambda *a: pytest.fail("the model ran on an empty window"))
    mean, std = prior.forecast(np.full((1, 64), np.nan), 16)
    assert np.isnan(mean).all() and np.isnan(std).all()


def test_beats_the_last_value_forecast_on_held_out_synthetic_series(prior):
    scores = score_prior(prior, synthetic_series(150, seed=12345))
    assert scores["n_windows"] > 500
    assert scores["mae_ratio"] < 1.0


def test_missing_or_corrupt_checkpoint_is_a_clear_error(tmp_path):
    with pytest.raises(CheckpointError, match="no Chronos-2 checkpoint"):
        Chronos2Prior(tmp_path / "nothing")
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "config.json").write_text((SHIPPED_PRIOR / "config.json").read_text())
    (bad / "model.safetensors").write_bytes(b"not a safetensors file")
    with pytest.raises(CheckpointError, match="could not load"):
        Chronos2Prior(bad)


def test_last_value_prior_holds_the_last_finite_value():
    mean, std = LastValuePrior().forecast(np.array([[1.0, 2.0, np.nan]]), 4)
    np.testing.assert_array_equal(mean, [[2.0] * 4])


def test_traced_forecasts_are_bit_identical_to_the_eager_model():
    import torch

    from racf.odca.prior import Chronos2Prior

    prior = Chronos2Prior(batch_size=8)
    rng = np.random.default_rng(3)
    ctx = rng.uniform(0.3, 4.0, (8, 64)).astype(np.float32)
    ctx[1, :40] = np.nan  # a series that starts late
    ctx[2, rng.random(64) < 0.3] = np.nan  # dropouts
    ctx[3, :-1] = np.nan  # one value
    ctx[4] = 0.0  # the padding rows' content
    x = torch.from_numpy(ctx)
    with torch.no_grad():
        eager = prior.model(x, group_ids=torch.arange(8), num_output_patches=1).quantile_preds
        traced = prior._forward(x, 1)
    assert torch.equal(eager, traced)


def test_loading_and_forecasting_print_nothing_and_leave_transformers_as_it_was(capfd):
    import logging

    from transformers.utils import logging as hf_logging

    logging.Logger.warning_once.cache_clear()  # transformers says a warning once per process
    before = (hf_logging.get_verbosity(), hf_logging.is_progress_bar_enabled())
    prior = Chronos2Prior()
    prior.forecast(np.linspace(2.0, 1.0, 64)[None], 16)
    assert (hf_logging.get_verbosity(), hf_logging.is_progress_bar_enabled()) == before
    err = capfd.readouterr().err
    assert "Loading weights" not in err and "loss_type" not in err, err
