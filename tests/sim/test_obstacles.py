"""The obstacle crates: placement, ground truth, and that they appear only in their own episodes."""

import gymnasium as gym
import numpy as np
import pytest

from racf import sim
from racf.controllers import ObstacleDetector
from racf.sim.world.obstacles import OBSTACLE_SIZE_M, STANDOFF_M, obstacles
from racf.sim.world.stop_signs import stop_signs


@pytest.fixture(scope="module")
def env():
    e = gym.make(sim.ENV_ID)
    yield e
    e.close()


def test_crates_stand_on_their_lanes_with_the_stop_line_before_them():
    for o in obstacles():
        s_face, lateral = o.path.project(np.asarray(o.position))
        assert abs(lateral) < 0.01
        assert s_face - o.stop_s == pytest.approx(STANDOFF_M, abs=0.01)
        # A straight of at least 1.2 m leads to the crate.
        i0, i1 = np.searchsorted(o.path.arclength, [o.stop_s - 1.2, s_face])
        assert np.abs(o.path.curvature[i0:i1]).max() < 1e-6
        assert o.corners().shape == (8, 3) and o.corners()[:, 2].max() == pytest.approx(OBSTACLE_SIZE_M[2])


@pytest.mark.parametrize("index", [0, 1])
def test_obstacle_episode_ground_truth_and_detection(env, index):
    obs, info = env.reset(seed=0, options={"obstacle": index, "cruise_speed": 0.0, "run_up_m": 1.0})
    assert info["target_kind"] == "obstacle" and info["sign_in_view"]
    mask = info["sign_mask"]
    depth = obs["depth"][..., 0][mask & (obs["depth"][..., 0] > 0)]
    # d_true is the near face's centre depth; the crate's visible pixels lie at or a little behind it.
    assert np.median(depth) == pytest.approx(info["d_true"], abs=0.05)
    assert info["d_true"] == pytest.approx(1.0 + STANDOFF_M + 0.1175, abs=0.05)
    det = ObstacleDetector().detect(obs["rgb"])
    assert det is not None and (det.mask & mask).sum() > 0.9 * det.area_px
    # The LiDAR sees it straight ahead (beams near 0 deg hit at about the crate's range).
    ahead = np.concatenate([obs["lidar"][-3:], obs["lidar"][:4]])
    assert np.nanmin(ahead) == pytest.approx(info["d_true"] + 0.107, abs=0.08)


def test_crates_are_absent_from_stop_sign_episodes(env):
    obs, info = env.reset(seed=0, options={"sign": 2, "cruise_speed": 0.0})
    assert info["target_kind"] == "stop_sign"
    for o in obstacles():
        assert env.unwrapped.data.body(f"obstacle_{o.index}").xpos[2] < -1.0
    assert ObstacleDetector().detect(obs["rgb"]) is None


def test_reset_rejects_sign_and_obstacle_together_and_bad_indices(env):
    with pytest.raises(ValueError, match="not both"):
        env.reset(options={"sign": 0, "obstacle": 0})
    with pytest.raises(ValueError, match=r"options\['obstacle'\] must be an int in 0..1"):
        env.reset(options={"obstacle": 5})
    assert len(stop_signs()) == 4 and len(obstacles()) == 2
