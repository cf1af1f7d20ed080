"""Rendered views for the segmenter: seeded, with ground-truth masks where the signs are."""

import numpy as np
import pytest

from racf.experiments.detector.dataset import DatasetSpec, load_split, make_dataset
from racf.experiments.detector.views import SIGN_RANGE_M, ViewRenderer, draw_view


@pytest.fixture(scope="module")
def renderer():
    r = ViewRenderer()
    yield r
    r.close()


def test_the_same_seed_draws_and_renders_the_same_views(renderer):
    a = [draw_view(np.random.default_rng(5), "sign") for _ in range(2)]
    assert a[0] == a[1]
    v0, v1 = renderer.render(a[0]), renderer.render(a[1])
    assert np.array_equal(v0.rgb, v1.rgb) and np.array_equal(v0.mask, v1.mask)


def test_sign_views_look_at_their_sign_within_range(renderer):
    rng = np.random.default_rng(1)
    seen = 0
    for _ in range(20):
        spec = draw_view(rng, "sign")
        view = renderer.render(spec)
        assert spec.sign in range(4)
        if view.target.sum() >= 12:
            seen += 1
            assert SIGN_RANGE_M[0] - 0.1 <= view.d_true <= SIGN_RANGE_M[1] + 0.1
            # The target's face is red where it is not the white border.
            red = view.rgb[view.target]
            assert (red[:, 0].astype(int) - red[:, 1] > 60).mean() > 0.3
            assert not (view.target & ~view.mask).any()
    assert seen >= 10  # the rest are far, edge-on or behind a moved prop


def test_moved_props_and_lighting_are_put_back(renderer):
    before = renderer.render(draw_view(np.random.default_rng(2), "sign", distractor_p=0.0))
    renderer.render(draw_view(np.random.default_rng(3), "map", distractor_p=1.0))
    renderer.restore()
    again = renderer.render(before.spec)
    assert np.array_equal(before.rgb, again.rgb)


def test_bad_kinds_and_specs_are_refused():
    with pytest.raises(ValueError, match="kind"):
        draw_view(np.random.default_rng(0), "room")
    with pytest.raises(ValueError, match="n_train"):
        DatasetSpec(n_train=0)


def test_a_dataset_is_written_in_shards_and_resumes(tmp_path):
    spec = DatasetSpec(seed=3, n_train=6, n_heldout=4)
    make_dataset(spec, tmp_path, progress=False)
    train = load_split(tmp_path, "train")
    assert train["rgb"].shape == (6, 240, 320, 3) and train["mask"].shape == (6, 240, 320)
    shard = tmp_path / "train" / "shard-000.npz"
    stamp = shard.stat().st_mtime_ns
    make_dataset(spec, tmp_path, progress=False)  # nothing to do: the shard is kept
    assert shard.stat().st_mtime_ns == stamp
    make_dataset(DatasetSpec(seed=4, n_train=6, n_heldout=4), tmp_path, progress=False)  # another spec: rendered anew
    assert not np.array_equal(load_split(tmp_path, "train")["rgb"], train["rgb"])


def test_a_dataset_mixes_its_kinds_of_view_and_far_views_stand_far(renderer):
    from racf.experiments.detector.dataset import draw_dataset_view
    from racf.experiments.detector.evaluate import VIEW_KINDS
    from racf.experiments.detector.views import FAR_RANGE_M

    rng = np.random.default_rng(11)
    specs = [draw_dataset_view(rng, DatasetSpec(far_share=0.5), renderer.camera_offset) for _ in range(300)]
    kinds = [s.kind for s in specs]
    assert set(kinds) == set(VIEW_KINDS)
    assert 0.3 < kinds.count("sign") / 300 < 0.6 and 0.2 < kinds.count("approach") / 300 < 0.4
    approach_signs = [s.sign for s in specs if s.kind == "approach"]
    assert approach_signs.count(1) > max(approach_signs.count(k) for k in (0, 2, 3))  # sign 1's geometry, twice
    far = [v for v in (renderer.render(s) for s in specs[:60] if s.kind == "sign") if v.d_true > SIGN_RANGE_M[1] + 0.2]
    assert far and all(v.d_true <= FAR_RANGE_M[1] + 0.1 for v in far)
    with pytest.raises(ValueError, match="sign_share \\+ approach_share"):
        DatasetSpec(sign_share=0.8, approach_share=0.3)
