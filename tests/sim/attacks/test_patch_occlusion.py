"""``PatchOcclusion``: a textured patch over a share of the sign's rows, in the RGB image only."""

import numpy as np
import pytest

from racf.sim.attacks import PatchOcclusion, patch_rows


@pytest.mark.parametrize("rho", [0.0, 0.3, 0.6, 0.9, 1.0])
def test_patch_covers_rho_of_the_sign_within_one_row_and_nothing_else(rho, stub_env, drive):
    env = PatchOcclusion(stub_env(), rho=rho, duration_s=5.0, trigger="always")
    checked = 0
    for obs, clean, info in drive(env, 25):
        mask = info["sign_mask"]
        if mask.sum() < 30:
            continue
        covered = patch_rows(mask, rho)
        widest_row = mask.sum(axis=1).max()
        assert abs(covered.sum() - rho * mask.sum()) <= widest_row
        changed = (obs["rgb"] != clean["rgb"]).any(axis=2)
        assert not (changed & ~covered).any(), "the patch drew outside its rows of the sign"
        assert changed.sum() >= 0.9 * covered.sum()
        np.testing.assert_array_equal(obs["depth"], clean["depth"])  # the patch lies on the face
        np.testing.assert_array_equal(obs["lidar"], clean["lidar"])
        assert info["attack"] == ("patch_occlusion",) and info["attack_active"]
        checked += 1
    assert checked > 5


def test_patch_is_textured_not_flat(stub_env, drive):
    env = PatchOcclusion(stub_env(), rho=1.0, duration_s=5.0, trigger="always")
    stds = [obs["rgb"][info["sign_mask"]].std(axis=0).mean() for obs, _, info in drive(env, 20)
            if info["sign_mask"].sum() > 30]
    assert len(stds) == 20 and min(stds) > 8.0  # the stub's sign is one flat colour


def test_patch_rows_takes_whole_top_rows_nearest_the_share():
    mask = np.zeros((12, 12), bool)
    mask[2:10, 3:7] = True  # 8 rows of 4 pixels
    np.testing.assert_array_equal(patch_rows(mask, 0.5), mask & (np.arange(12) < 6)[:, None])
    np.testing.assert_array_equal(patch_rows(mask, 1.0), mask)
    assert patch_rows(mask, 0.3).sum() == 8  # 9.6 pixels: the nearest row boundary is 2 rows
    assert not patch_rows(mask, 0.0).any()
    assert not patch_rows(np.zeros((12, 12), bool), 0.7).any()


@pytest.mark.parametrize("kwargs", [{"rho": 1.5}, {"rho": -0.1}, {"rho": (0.8, 0.2)}])
def test_bad_rho_is_a_value_error(kwargs, stub_env):
    with pytest.raises(ValueError, match="rho"):
        PatchOcclusion(stub_env(), **kwargs)
