"""The sticker on the stop sign: placement on the plate, and how the scene renders it."""

import math

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf import sim
from racf.sim.world.sign_patch import OCTAGON_AREA, POSITIONS, PatchPlacement, load_patch_texture
from racf.sim.world.stop_signs import SIGN_FACE_ACROSS_FLATS_M, stop_signs


@given(st.floats(0.01, 0.6), st.sampled_from(sorted(POSITIONS)))
@settings(max_examples=60, deadline=None)
def test_named_positions_keep_any_size_on_the_plate(area, name):
    p = PatchPlacement(area_share=area, centre=name)
    corners = p.corners_local(stop_signs()[0].geometry)[:, 1:]
    centre = np.array([0.0, stop_signs()[0].geometry.centre_height_m])
    xy = (corners - centre) / SIGN_FACE_ACROSS_FLATS_M
    assert np.all(np.abs(xy) <= 0.5 + 1e-6) and np.all(np.abs(xy).sum(axis=1) <= 0.5 * math.sqrt(2) + 1e-6)
    assert p.side_m ** 2 == pytest.approx(area * OCTAGON_AREA * SIGN_FACE_ACROSS_FLATS_M ** 2)


@pytest.mark.parametrize("bad, match", [({"area_share": 0.7}, "area_share"), ({"area_share": True}, "area_share"),
                                        ({"centre": (0.4, 0.0)}, "leaves the plate"),
                                        ({"centre": "middle"}, "centre"), ({"centre": (0.9, 0.0)}, r"\[-0.5, 0.5\]")])
def test_bad_placements_are_refused_by_name(bad, match):
    with pytest.raises(ValueError, match=match):
        PatchPlacement(**bad)


def test_an_unknown_texture_names_the_shipped_ones():
    with pytest.raises(ValueError, match="shipped"):
        load_patch_texture("nope")
    assert load_patch_texture("natural", np.random.default_rng(0)).shape == (64, 64, 3)


@pytest.fixture(scope="module")
def env():
    e = gym.make(sim.ENV_ID)
    yield e
    e.close()


def _quadrants():
    tex = np.zeros((64, 64, 3), np.uint8)
    tex[:32, :32] = (255, 0, 0)
    tex[:32, 32:] = (0, 255, 0)
    tex[32:, 32:] = (0, 0, 255)
    return tex


def test_the_sticker_renders_upright_and_unmirrored_where_its_corners_project(env):
    from racf.sim.env.ground_truth import _MJ_TO_OPTICAL

    obs, _ = env.reset(seed=0, options={"sign": 2, "cruise_speed": 0.0, "run_up_m": 0.5})
    u = env.unwrapped
    placement = PatchPlacement(area_share=0.5)
    u.show_sign_patch(2, _quadrants(), placement)
    obs, _ = u.retake_reset_frame()
    cam_pos, cam_mat = u.car.camera_pose(u.model, u.data)
    opt = (_MJ_TO_OPTICAL @ cam_mat.T @ (placement.corners_world(stop_signs()[2]) - cam_pos).T).T
    uv = u.rig.intrinsics.project(opt)
    centre = uv.mean(axis=0)
    for corner, colour in zip(uv, ((255, 0, 0), (0, 255, 0), (0, 0, 255), (0, 0, 0))):
        probe = np.round(centre + 0.5 * (corner - centre)).astype(int)
        pixel = obs["rgb"][probe[1], probe[0]].astype(int)
        assert np.argmax(pixel) == np.argmax(colour) or (max(colour) == 0 and pixel.max() < 60), (colour, pixel)
    env.reset(seed=0, options={"sign": 2, "cruise_speed": 0.0, "run_up_m": 0.5})  # the reset takes it off
    assert (u.model.geom_group[u.stickers.geoms] == 5).all()


def test_the_lidar_sees_the_plate_with_the_sticker_as_without(env):
    obs0, _ = env.reset(seed=3, options={"sign": 2, "cruise_speed": 0.0, "run_up_m": 0.8})
    env.unwrapped.show_sign_patch(2, _quadrants(), PatchPlacement(area_share=0.5))
    obs1, _ = env.unwrapped.retake_reset_frame()
    d0, d1 = obs0["depth"][..., 0], obs1["depth"][..., 0]
    face = env.unwrapped._info(collision=False, off_road=False)["sign_mask"]
    assert abs(float(np.median(d0[face & (d0 > 0)])) - float(np.median(d1[face & (d1 > 0)]))) < 0.005
    assert not np.array_equal(obs0["rgb"], obs1["rgb"])
