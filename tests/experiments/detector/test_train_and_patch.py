"""Training the segmenter and optimising the sticker: seeded, refusing bad settings before any work."""

import numpy as np
import pytest
import torch

from racf.experiments.detector.dataset import DatasetSpec, make_dataset
from racf.experiments.detector.patch_opt import PatchConfig, composite, optimise_patch
from racf.experiments.detector.train import TrainConfig, train_segmenter


@pytest.fixture(scope="module")
def tiny_data(tmp_path_factory):
    root = tmp_path_factory.mktemp("views")
    make_dataset(DatasetSpec(seed=7, n_train=24, n_heldout=4, sign_share=1.0, approach_share=0.0), root, progress=False)
    return root


def test_training_is_seeded_and_reports_its_held_out_scores(tiny_data, tmp_path):
    config = TrainConfig(epochs=1, batch=8, threads=1)
    a, report = train_segmenter(config, tiny_data, tmp_path / "ck", progress=False)
    b, _ = train_segmenter(config, tiny_data, progress=False)
    for pa, pb in zip(a.state_dict().values(), b.state_dict().values()):
        torch.testing.assert_close(pa, pb)
    assert report["heldout"]["n_frames"] == 4 and (tmp_path / "ck" / "model.pt").is_file()
    c, _ = train_segmenter(TrainConfig(epochs=1, batch=8, threads=1, seed=1), tiny_data, progress=False)
    assert not torch.equal(next(iter(a.state_dict().values())), next(iter(c.state_dict().values())))


def test_the_sticker_is_seeded(tiny_data):
    config = PatchConfig(steps=3, batch=4, min_sign_px=12, threads=1)
    t1, report = optimise_patch(config, tiny_data, progress=False)
    t2, _ = optimise_patch(config, tiny_data, progress=False)
    assert t1.shape == (64, 64, 3) and t1.dtype == np.uint8
    assert np.abs(t1.astype(int) - t2).max() <= 1
    assert report["n_views"] >= 4


@pytest.mark.parametrize("bad, match", [({"size": 0.9}, "area_share"), ({"position": (0.5, 0.5)}, "plate"),
                                        ({"steps": 0}, "steps"), ({"lr": -1.0}, "lr"), ({"views": "random"}, "views"),
                                        ({"n_approach": 0}, "n_approach")])
def test_bad_patch_settings_fail_before_any_work(bad, match):
    with pytest.raises(ValueError, match=match):
        PatchConfig(**bad)


def test_bad_training_settings_fail_before_any_work():
    with pytest.raises(ValueError, match="epochs"):
        TrainConfig(epochs=0)


def test_the_warp_puts_the_texture_on_its_corners_unmirrored():
    tex = torch.zeros(3, 64, 64)
    tex[0, :32, :32] = 1.0  # red top-left quadrant
    tex[2, 32:, 32:] = 1.0  # blue bottom-right
    images = torch.zeros(1, 3, 120, 160)
    corners = torch.tensor([[[40.0, 20.0], [120.0, 20.0], [120.0, 100.0], [40.0, 100.0]]])
    out = composite(images, tex, corners, torch.ones(1, 1, 120, 160), torch.ones(1, 3, 1, 1))
    assert out[0, 0, 40, 60] > 0.9 and out[0, 2, 40, 60] < 0.1      # top-left: red
    assert out[0, 2, 80, 100] > 0.9 and out[0, 0, 80, 100] < 0.1    # bottom-right: blue
    assert out[0, :, 10, 10].abs().max() < 1e-6                      # outside the sticker: the frame


def test_the_sticker_can_be_optimised_over_approach_views(monkeypatch):
    """views="approach" renders the car's approach views itself (no dataset) and weighs each."""
    from racf.experiments.detector import approach_views as av

    seen, render = {}, av.approach_views

    def few(n, seed=0, progress=False):
        seen["n"] = n
        return render(24, seed)

    monkeypatch.setattr(av, "approach_views", few)
    config = PatchConfig(steps=2, batch=4, min_sign_px=12, threads=1, views="approach", n_approach=24)
    texture, report = optimise_patch(config, progress=False)
    assert seen["n"] == 24 and texture.shape == (64, 64, 3) and report["config"]["views"] == "approach"


def test_pasted_red_shapes_are_red_away_from_every_face_and_seeded():
    from torch.nn import functional as F

    from racf.experiments.detector.train import paste_red_shapes

    x = torch.full((6, 3, 96, 128), 0.8)
    faces = torch.zeros(6, 1, 96, 128)
    faces[:, :, 10:30, 10:30] = 1.0
    y = F.avg_pool2d(faces, 2)
    a, b = x.clone(), x.clone()
    paste_red_shapes(a, y, torch.Generator().manual_seed(3), 1.0)
    paste_red_shapes(b, y, torch.Generator().manual_seed(3), 1.0)
    assert torch.equal(a, b)
    changed = (a != x).any(dim=1)
    assert changed.any()
    near = F.max_pool2d(faces, 5, stride=1, padding=2)[:, 0] > 0
    assert not (changed & near).any()  # a face and its surround are never painted over
    red = a.permute(0, 2, 3, 1)[changed]
    assert (red[:, 0] > red[:, 1] + 0.1).all() and (red[:, 0] > red[:, 2] + 0.1).all()
    with pytest.raises(ValueError, match="unknown shapes.*square"):
        paste_red_shapes(a, y, torch.Generator(), 1.0, kinds=("star",))
