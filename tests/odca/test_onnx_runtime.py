"""ODCA onboard: the shipped ONNX export runs in onnxruntime and gives the PyTorch path's numbers
within 1e-5 m; what an export holds, and what is refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from racf.odca import ODCA
from racf.odca.onnx_runtime import SHIPPED_ONNX, OnnxPrior, read_export
from racf.odca.prior import CheckpointError, Chronos2Prior
from racf.odca.synthetic import approach_curve


@pytest.fixture(scope="module")
def models():
    return ODCA.load(), ODCA.load(runtime="onnx")


def test_the_exported_prior_forecasts_what_pytorch_forecasts():
    torch_prior, onnx_prior = Chronos2Prior(), OnnxPrior(SHIPPED_ONNX)
    rng = np.random.default_rng(0)
    windows = np.cumsum(rng.normal(0, 0.05, (6, 64)), axis=1) + 2.0
    windows[1, :40] = np.nan  # a young window: mostly missing
    windows[2, ::3] = np.nan
    windows[3] = np.nan  # nothing at all: NaN from both
    a, b = torch_prior.forecast(windows, 16), onnx_prior.forecast(windows, 16)
    for x, y in zip(a, b):
        assert np.array_equal(np.isnan(x), np.isnan(y))
        assert np.nanmax(np.abs(x - y)) < 1e-5


def test_a_context_shorter_than_the_priors_forecasts_what_pytorch_forecasts():
    """A short window is padded with missing values, as the PyTorch prior reads it (zeros would be
    distances of 0 m)."""
    torch_prior, onnx_prior = Chronos2Prior(), OnnxPrior(SHIPPED_ONNX)
    short = 2.0 - 0.02 * np.arange(min(12, onnx_prior.context_length - 1), dtype=float)[None, :]
    a, b = torch_prior.forecast(short, 16), onnx_prior.forecast(short, 16)
    for x, y in zip(a, b):
        assert np.nanmax(np.abs(x - y)) < 1e-5


def test_onboard_odca_repairs_an_attacked_approach_as_pytorch_does(models):
    torch_model, onnx_model = models
    rng = np.random.default_rng(1)
    depth = approach_curve(rng, 400)
    lidar = depth + rng.normal(0, 0.01, depth.size)
    depth[150:220] += 0.9  # a bias attack: the gate repairs it
    depth[rng.random(depth.size) < 0.1] = np.nan
    out = []
    for model in (torch_model, onnx_model):
        model.reset()
        out.append(np.array([model.step(depth=float(d), confidence=0.9, lidar=float(l), speed=1.0).d_fused
                             for d, l in zip(depth, lidar)]))
    assert np.array_equal(np.isnan(out[0]), np.isnan(out[1]))
    assert np.nanmax(np.abs(out[0] - out[1])) < 1e-5
    assert onnx_model.head.n_parameters == torch_model.head.n_parameters == 917


def test_the_shipped_export_is_of_the_shipped_checkpoint():
    from racf.odca.online import SHIPPED_HEAD
    from racf.odca.onnx_export import _sha

    manifest = read_export(SHIPPED_ONNX)
    assert manifest["source"] == "shipped" and manifest["prior"]["context_length"] == 64
    for name in ("odca.json", "head.npz"):
        assert manifest["source_sha"][name] == _sha(SHIPPED_HEAD / name) == _sha(SHIPPED_ONNX / name)
    assert json.loads((SHIPPED_ONNX / "odca.json").read_text()) == json.loads((SHIPPED_HEAD / "odca.json").read_text())


def test_a_folder_without_an_export_is_one_line(tmp_path):
    with pytest.raises(CheckpointError, match="racf odca export"):
        ODCA.load(tmp_path, runtime="onnx")
    with pytest.raises(ValueError, match="runtime must be one of"):
        ODCA.load(runtime="tflite")


def test_an_export_refuses_a_folder_with_files(tmp_path):
    from racf.errors import UserError
    from racf.odca.onnx_export import export_onnx

    (tmp_path / "x").write_text("keep me")
    with pytest.raises(UserError, match="not empty"):
        export_onnx(tmp_path)
    assert (tmp_path / "x").read_text() == "keep me"


@pytest.mark.slow
def test_an_export_gives_the_shipped_models_again(tmp_path):
    """The export is reproducible in what it computes (the ONNX bytes themselves carry the exporter's
    names): exporting the shipped checkpoint anew forecasts and corrects as the shipped export does."""
    from racf.odca.onnx_export import export_onnx

    export_onnx(tmp_path / "out")
    fresh, shipped = OnnxPrior(tmp_path / "out"), OnnxPrior(SHIPPED_ONNX)
    windows = np.cumsum(np.random.default_rng(2).normal(0, 0.05, (4, 64)), axis=1) + 2.0
    for a, b in zip(fresh.forecast(windows, 16), shipped.forecast(windows, 16)):
        assert np.allclose(a, b, rtol=0.0, atol=1e-6)
    a, b = ODCA.load(tmp_path / "out", runtime="onnx").head, ODCA.load(runtime="onnx").head
    x = np.random.default_rng(3).normal(0, 1, (8, 10))
    assert np.allclose(a(x), b(x), rtol=0.0, atol=1e-6)
