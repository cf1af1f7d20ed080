"""The referee's truth follows the world, not the map: a world manager that turns and leans a
stop sign's body moves the sign's mask, its view and its distance with it (checked against
MuJoCo's own segmentation render of the plate), a sign taken off the floor stands nowhere, and
the image-space patch, placed by that truth, acts on the turned sign."""

from __future__ import annotations

import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.ndimage import binary_dilation

import racf.sim as sim
from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.scenarios import Param, Scenario
from racf.plugins import SCENARIOS
from racf.sim.env.ground_truth import Motion
from racf.sim.env.world import WorldManager
from racf.sim.world.scene import sign_body

TURN_DEG, LEAN_DEG = 40.0, 30.0


def _axis_quat(axis, angle_rad: float) -> np.ndarray:
    return np.array([math.cos(angle_rad / 2), *(math.sin(angle_rad / 2) * np.asarray(axis, float))])


def _times(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, np.asarray(a, float), np.asarray(b, float))
    return out


class TurnedSign(WorldManager):
    """Turns stop sign ``k`` about its pole by ``turn`` degrees and leans it back by ``lean`` (the
    reset option ``turned_sign``: ``(k, turn, lean)``); every other sign stands as the map says."""

    name = option = "turned_sign"

    def bind(self, model) -> None:
        self._bodies = {k: model.body(sign_body(k)).id for k in range(4)}
        self._home = {k: model.body_quat[b].copy() for k, b in self._bodies.items()}

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        for k, body in self._bodies.items():
            model.body_quat[body] = self._home[k]
        if value is not None:
            k, turn, lean = value
            turned = _times(self._home[k], _axis_quat((0, 0, 1), math.radians(turn)))
            model.body_quat[self._bodies[k]] = _times(turned, _axis_quat((0, 1, 0), -math.radians(lean)))


class TurnedSignApproach(Scenario):
    """The approach to a stop sign whose body a world manager turned and leaned."""

    name = "turned_sign_test"
    meaning = "a stop-sign approach to a turned, leaning sign (a test's)"
    params = (Param("turn_deg", TURN_DEG, -60.0, 60.0, unit="deg", meaning="turn about the pole"),
              Param("lean_deg", LEAN_DEG, 0.0, 45.0, unit="deg", meaning="lean backwards"))

    def world(self, spec, values):
        return (TurnedSign(),)

    def plan(self, spec, values, draft):
        options = {**draft.reset_options, "turned_sign": (spec.sign, values["turn_deg"], values["lean_deg"])}
        return self.replace(draft, reset_options=options)


def _plate_pixels(env, index: int) -> np.ndarray:
    """The pixels MuJoCo's segmentation render gives sign ``index``'s plate (face and border) from
    the car's camera now."""
    base = env.unwrapped
    renderer = mujoco.Renderer(base.model, base.config.camera.height, base.config.camera.width)
    try:
        renderer.enable_segmentation_rendering()
        renderer.update_scene(base.data, camera="d435")
        seg = renderer.render()
    finally:
        renderer.close()
    plate = [base.model.geom(f"{sign_body(index)}_{part}").id for part in ("face", "border")]
    return np.isin(seg[..., 0], plate) & (seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM))


@pytest.fixture(scope="module")
def turned_env():
    env = gym.make(sim.ENV_ID, world=(TurnedSign(),), camera_width=160, camera_height=120)
    yield env
    env.close()


@pytest.mark.parametrize("run_up_m", [0.6, 1.0])
def test_the_mask_of_a_turned_leaning_sign_is_the_rendered_plate(turned_env, run_up_m):
    # The reset's frame is taken where the world stands at the reset: the same state renders here.
    _, info = turned_env.reset(seed=0, options={"sign": 2, "cruise_speed": 1.0, "run_up_m": run_up_m,
                                                "turned_sign": (2, TURN_DEG, LEAN_DEG)})
    plate, mask = _plate_pixels(turned_env, 2), info["sign_mask"]
    assert plate.sum() >= 30 and info["sign_in_view"] and info["target_stands"]
    near = np.ones((5, 5), bool)  # within two pixels, either way
    assert not (mask & ~binary_dilation(plate, near)).any()
    assert not (plate & ~binary_dilation(mask, near)).any()
    # The distance follows the body too: the plate's centre where the turned body holds it.
    base = turned_env.unwrapped
    body = base.model.body(sign_body(2)).id
    centre = base.data.xpos[body] + base.data.xmat[body].reshape(3, 3) @ [0, 0, base.target_sign.centre[2]]
    cam_pos, cam_mat = base.car.camera_pose(base.model, base.data)
    depth = -(np.asarray(cam_mat).reshape(3, 3).T @ (centre - np.asarray(cam_pos)))[2]
    assert info["d_true"] == pytest.approx(depth, abs=1e-9)


def test_a_sign_taken_off_the_floor_stands_nowhere():
    from racf.sim.env.sign_props import SignPropsManager

    env = gym.make(sim.ENV_ID, world=(SignPropsManager(),), camera_width=160, camera_height=120)
    try:
        _, removed = env.reset(seed=0, options={"sign": 2, "cruise_speed": 1.0, "run_up_m": 0.6,
                                                "sign_props": {"remove": 2, "phantom": None}})
        _, standing = env.reset(seed=0, options={"sign": 2, "cruise_speed": 1.0, "run_up_m": 0.6})
    finally:
        env.close()
    assert not removed["target_stands"] and not removed["sign_in_view"]
    assert standing["target_stands"] and standing["sign_in_view"]


def test_a_body_at_its_map_pose_has_no_motion():
    pos, mat = np.array([1.0, 2.0, 0.0]), np.eye(3).reshape(-1)
    assert Motion.between(pos, mat, pos.copy(), mat.copy()) is None
    assert Motion.between(pos, mat, pos + [0, 0, 1e-12], mat) is not None


@given(st.floats(-math.pi, math.pi), st.floats(-1.0, 1.0), st.lists(st.floats(-2, 2), min_size=3, max_size=3))
def test_a_motion_is_rigid_and_takes_the_origin_to_the_body(yaw, lean, shift):
    home_pos, home_mat = np.array([0.5, -1.0, 0.0]), np.eye(3)
    c, s, cl, sl = math.cos(yaw), math.sin(yaw), math.cos(lean), math.sin(lean)
    mat = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ np.array([[cl, 0, sl], [0, 1, 0], [-sl, 0, cl]])
    motion = Motion.between(home_pos, home_mat, home_pos + shift, mat)
    if motion is None:  # no motion at all: the record stands as it is
        assert np.array_equal(home_pos + shift, home_pos) and np.array_equal(mat, home_mat)
        return
    points = np.array([[0.6, -1.0, 0.23], [0.5, -0.9, 0.1], [1.0, 1.0, 1.0]])
    moved = motion.points(points)
    assert np.allclose(motion.points(home_pos), home_pos + shift)
    assert np.allclose(np.linalg.norm(moved[:, None] - moved[None], axis=2),
                       np.linalg.norm(points[:, None] - points[None], axis=2))


def test_the_patch_acts_on_a_turned_sign_and_t_star_is_defined():
    """Placed by the world's truth, the image-space patch covers the turned sign the camera sees."""
    SCENARIOS.register(TurnedSignApproach)
    try:
        result, log = run_trial(TrialSpec("attack", 2, 1.0, 0, target=TurnedSignApproach.name))
    finally:
        SCENARIOS._all().pop(TurnedSignApproach.name)
    assert log["sign_in_view"].any()
    assert math.isfinite(result.t_star_s)
    assert result.lost_frames > 0
