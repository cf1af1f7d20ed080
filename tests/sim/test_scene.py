"""The compiled map: the stop signs built to a ``SignGeometry``, as the LiDAR's scan plane meets them."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from racf.sim.world.scene import build_scene_xml, load_model
from racf.sim.world.stop_signs import (
    PLATE_IN_SCAN,
    POLE_ONLY,
    SIGN_CENTRE_HEIGHT_M,
    SignGeometry,
    stop_signs,
)

#: Height of the car's LiDAR scan plane above the floor (tests/sim/test_sensors.py).
LIDAR_Z = 0.193
#: The groups the LiDAR sees (sim/sensors/lidar.py): map and props, not the car.
VISIBLE_GROUPS = np.array([1, 1, 1, 0, 0, 0], dtype=np.uint8)
SIGN_IDS = [f"sign{i}" for i in range(4)]


@pytest.fixture(scope="module")
def worlds():
    out = {}
    for name, geometry in (("plate", PLATE_IN_SCAN), ("pole", POLE_ONLY)):
        model = load_model(sign_geometry=geometry)
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        out[name] = (model, data)
    return out


def _geom(model, name):
    return model.geom(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name))


def _ray_at_sign(model, data, index, lateral_m=0.0, ahead_m=0.3, z=LIDAR_Z):
    """Casts a horizontal ray at height ``z`` from ``ahead_m`` in front of sign ``index``,
    towards the sign against its face normal, ``lateral_m`` to the side of its centre line.
    Returns (the body the hit geom belongs to, the geom's name, distance); (None, None, -1)
    for no hit. Unnamed geoms (other props) have name None."""
    sign = stop_signs()[index]
    normal = np.array([math.cos(sign.face_yaw), math.sin(sign.face_yaw), 0.0])
    left = np.array([-math.sin(sign.face_yaw), math.cos(sign.face_yaw), 0.0])
    start = np.array([*sign.position, z]) + ahead_m * normal + lateral_m * left
    geomid = np.array([-1], dtype=np.int32)
    dist = mujoco.mj_ray(model, data, start, -normal, VISIBLE_GROUPS, 1, -1, geomid)
    if geomid[0] < 0:
        return None, None, dist
    body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.geom_bodyid[geomid[0]]))
    return body, mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(geomid[0])), dist


def test_default_scene_keeps_the_old_numbers(worlds):
    model, _ = worlds["plate"]
    assert build_scene_xml() == build_scene_xml(PLATE_IN_SCAN) == build_scene_xml(SignGeometry(0.18, 0.008))
    for i in range(4):
        pole = _geom(model, f"stop_sign_{i}_pole")
        assert pole.size[0] == pytest.approx(0.004, abs=1e-12)
        assert pole.size[1] == pytest.approx(SIGN_CENTRE_HEIGHT_M / 2, abs=1e-12)
        assert pole.pos[2] == pytest.approx(SIGN_CENTRE_HEIGHT_M / 2, abs=1e-12)
        assert _geom(model, f"stop_sign_{i}_border").pos[2] == pytest.approx(0.23, abs=1e-9)


@pytest.mark.parametrize("geometry", [PLATE_IN_SCAN, POLE_ONLY, SignGeometry(0.4, 0.02)], ids=str)
def test_pole_reaches_the_plate_and_plate_stands_where_the_geometry_says(geometry):
    model = load_model(sign_geometry=geometry)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    for i in range(4):
        pole = _geom(model, f"stop_sign_{i}_pole")
        radius, half = pole.size[0], pole.size[1]
        assert radius == pytest.approx(geometry.pole_diameter_m / 2, abs=1e-12)
        assert pole.pos[2] - half == pytest.approx(0.0, abs=1e-12)  # stands on the floor
        top = pole.pos[2] + half
        assert geometry.plate_bottom_m < top <= geometry.plate_top_m  # reaches into the plate
        # The plate's vertices in the world: its lowest (an octagon's flat) is the plate bottom.
        border = _geom(model, f"stop_sign_{i}_border")
        mesh = model.mesh(border.dataid[0])
        verts = model.mesh_vert[mesh.vertadr[0]:mesh.vertadr[0] + mesh.vertnum[0]]
        world = data.geom(border.id).xpos + verts @ data.geom(border.id).xmat.reshape(3, 3).T
        assert world[:, 2].min() == pytest.approx(geometry.plate_bottom_m, abs=1e-6)
        assert world[:, 2].max() == pytest.approx(geometry.plate_top_m, abs=1e-6)
        assert world[:, 2].mean() == pytest.approx(geometry.centre_height_m, abs=1e-6)


def test_models_are_fresh_copies_per_call():
    a, b = load_model(sign_geometry=POLE_ONLY), load_model(sign_geometry=POLE_ONLY)
    assert a is not b
    assert _geom(a, "stop_sign_0_pole").size[0] == pytest.approx(0.003)
    assert _geom(load_model(), "stop_sign_0_pole").size[0] == pytest.approx(0.004)


@pytest.mark.parametrize("index", range(4), ids=SIGN_IDS)
def test_scan_plane_meets_the_plate_by_default(worlds, index):
    model, data = worlds["plate"]
    _, name, dist = _ray_at_sign(model, data, index)
    assert name in (f"stop_sign_{index}_face", f"stop_sign_{index}_border")
    assert dist == pytest.approx(0.3 - 0.001, abs=2e-3)  # the face stands 1 mm proud of the border
    # 10 mm to the side, still on the 0.10 m plate.
    _, name, _ = _ray_at_sign(model, data, index, lateral_m=0.010)
    assert name in (f"stop_sign_{index}_face", f"stop_sign_{index}_border")


@pytest.mark.parametrize("index", range(4), ids=SIGN_IDS)
def test_scan_plane_meets_only_the_pole_for_pole_only(worlds, index):
    model, data = worlds["pole"]
    _, name, dist = _ray_at_sign(model, data, index)
    assert name == f"stop_sign_{index}_pole"
    assert dist == pytest.approx(0.3 + 0.003, abs=1e-6)  # the pole's front, just behind the 3 mm plate
    # Aimed 10 mm to the side of the pole's centre (either side), the ray misses the sign.
    for lateral in (0.010, -0.010):
        body, name, dist = _ray_at_sign(model, data, index, lateral_m=lateral)
        assert body is None or not body.startswith("stop_sign_"), (body, name)
        assert dist < 0 or dist > 0.5  # nothing near the sign: a wall or another prop far behind
    # The plate is still there, above the scan plane.
    _, name, _ = _ray_at_sign(model, data, index, z=POLE_ONLY.centre_height_m)
    assert name in (f"stop_sign_{index}_face", f"stop_sign_{index}_border")


def test_load_model_rejects_a_non_geometry():
    with pytest.raises(TypeError, match="sign_geometry must be a SignGeometry"):
        load_model(sign_geometry=0.21)
