"""Builds the MuJoCo model of the indoor map with the QCar 2 on it.

The map is generated from the official facts (``map_facts``): the floor mat texture from
the road graph, the walls, the four stop signs (red octagon with a white border on a pole,
built to a ``SignGeometry``: the plate's height and the pole's diameter), the traffic lights
and yield signs as static props. The car comes from
``assets/qcar2_map/qcar2.xml`` through an ``<include>``. Nothing here knows gymnasium.
"""

from __future__ import annotations

import math
import os
from functools import lru_cache
from pathlib import Path

from racf.assets import asset_path
from racf.sim._gl import ensure_gl_backend

ensure_gl_backend()
import mujoco  # noqa: E402  (the GL backend must be chosen before mujoco is imported)

from racf.sim.world import map_facts  # noqa: E402
from racf.sim.world.mat_texture import mat_png_bytes  # noqa: E402
from racf.sim.world.obstacles import OBSTACLE_SIZE_M, obstacles  # noqa: E402
from racf.sim.world.sign_patch import PATCH_FRONT_X_M, TEXTURE_PX  # noqa: E402
from racf.sim.world.stop_signs import (  # noqa: E402
    PLATE_IN_SCAN,
    SIGN_CENTRE_HEIGHT_M,
    SIGN_FACE_ACROSS_FLATS_M,
    SIGN_RED_FACE_ACROSS_FLATS_M,
    SignGeometry,
    stop_signs,
)

__all__ = ["ASSETS_DIR", "build_scene_xml", "load_model", "PROP_GEOM_GROUP", "CAR_GEOM_GROUP", "HIDDEN_GEOM_GROUP",
           "patch_geom", "patch_texture", "sign_body", "obstacle_body", "car_xml"]

ASSETS_DIR = Path(os.environ["RACF_ASSETS"]) if "RACF_ASSETS" in os.environ else asset_path("qcar2_map")
#: Geom groups: 0 map and props (seen by camera and LiDAR), 3 the car (skipped by the LiDAR).
PROP_GEOM_GROUP = 0
CAR_GEOM_GROUP = 3
#: Largest offscreen image any sensor or snapshot may ask for.
MAX_IMAGE_SIZE = (1280, 960)

_SIGN_THICKNESS_M = 0.003
#: Half the thickness of the sticker each stop sign carries (``racf.sim.world.sign_patch``).
_PATCH_HALF_THICKNESS_M = 0.0001
#: Geom group of what exists but no sensor sees: the stickers until the env shows one (the
#: camera renders groups 0-2, the LiDARs hit groups 0-2).
HIDDEN_GEOM_GROUP = 5
#: The yield signs' pole (their build is not a scenario parameter).
_POLE_RADIUS_M = 0.004


def _octagon_mesh(name: str, across_flats: float, thickness: float) -> str:
    """An octagonal plate in its local y-z plane, face normal +x."""
    r = across_flats / (2 * math.cos(math.pi / 8))
    verts = []
    for x in (0.0, -thickness):
        for k in range(8):
            a = math.pi / 8 + k * math.pi / 4
            verts += [x, r * math.cos(a), r * math.sin(a)]
    return f'<mesh name="{name}" vertex="{" ".join(f"{v:.6f}" for v in verts)}"/>'


def _triangle_mesh(name: str, side: float, thickness: float) -> str:
    """A point-down triangle plate in its local y-z plane, face normal +x, centred."""
    h = side * math.sqrt(3) / 2
    corners = [(-side / 2, h / 3), (side / 2, h / 3), (0.0, -2 * h / 3)]
    verts = [v for x in (0.0, -thickness) for (y, z) in corners for v in (x, y, z)]
    return f'<mesh name="{name}" vertex="{" ".join(f"{v:.6f}" for v in verts)}"/>'


def _stop_sign_xml(index: int, x: float, y: float, yaw: float, geometry: SignGeometry) -> str:
    # The pole stands just behind the plate and reaches up to the plate's centre.
    z, r = geometry.centre_height_m, geometry.pole_radius_m
    return f"""
    <body name="{sign_body(index)}" pos="{x} {y} 0" euler="0 0 {math.degrees(yaw):.4f}">
      <geom name="stop_sign_{index}_pole" type="cylinder" pos="{-_SIGN_THICKNESS_M - r} 0 {z / 2}"
            size="{r} {z / 2}" rgba="0.55 0.55 0.58 1"/>
      <geom name="stop_sign_{index}_border" type="mesh" mesh="stop_octagon_border" pos="0 0 {z}" rgba="0.97 0.97 0.97 1"/>
      <geom name="stop_sign_{index}_face" type="mesh" mesh="stop_octagon_face" pos="0.001 0 {z}"
            rgba="0.80 0.05 0.06 1" contype="0" conaffinity="0"/>
      <geom name="stop_sign_{index}_patch" type="box" pos="{PATCH_FRONT_X_M - _PATCH_HALF_THICKNESS_M} 0 {z}"
            size="{_PATCH_HALF_THICKNESS_M} 0.02 0.02" material="stop_sign_{index}_patch" contype="0" conaffinity="0"
            group="{HIDDEN_GEOM_GROUP}"/>
    </body>"""


def sign_body(index: int) -> str:
    """Name of stop sign ``index``'s body (its frame: x along the face's normal, z up, origin at the
    pole's foot on the floor; the plate's centre at z = the geometry's ``centre_height_m``)."""
    return f"stop_sign_{index}"


def obstacle_body(index: int) -> str:
    """Name of crate ``index``'s body."""
    return f"obstacle_{index}"


def patch_geom(index: int) -> str:
    """Name of stop sign ``index``'s sticker geom."""
    return f"stop_sign_{index}_patch"


def patch_texture(index: int) -> str:
    """Name of stop sign ``index``'s sticker texture."""
    return f"stop_sign_{index}_patch"


def _patch_assets() -> str:
    return "".join(
        f'\n    <texture name="{patch_texture(i)}" type="2d" builtin="flat" width="{TEXTURE_PX}" height="{TEXTURE_PX}"'
        f' rgb1="0.5 0.5 0.5"/>\n    <material name="{patch_texture(i)}" texture="{patch_texture(i)}"'
        ' specular="0" shininess="0" reflectance="0"/>' for i in range(len(map_facts.STOP_SIGNS)))


def _traffic_light_xml(index: int, x: float, y: float, yaw_deg: float) -> str:
    return f"""
    <body name="traffic_light_{index}" pos="{x} {y} 0" euler="0 0 {yaw_deg}">
      <geom type="cylinder" pos="0 0 0.15" size="0.006 0.15" rgba="0.3 0.3 0.32 1"/>
      <geom type="box" pos="0 0 0.33" size="0.015 0.02 0.05" rgba="0.08 0.08 0.08 1"/>
      <geom type="cylinder" pos="0.016 0 0.36" size="0.008 0.002" euler="0 90 0" rgba="0.6 0.05 0.05 1" contype="0" conaffinity="0"/>
      <geom type="cylinder" pos="0.016 0 0.33" size="0.008 0.002" euler="0 90 0" rgba="0.6 0.5 0.05 1" contype="0" conaffinity="0"/>
      <geom type="cylinder" pos="0.016 0 0.30" size="0.008 0.002" euler="0 90 0" rgba="0.1 0.8 0.2 1" contype="0" conaffinity="0"/>
    </body>"""


def _yield_sign_xml(index: int, x: float, y: float, yaw_deg: float) -> str:
    z = SIGN_CENTRE_HEIGHT_M
    return f"""
    <body name="yield_sign_{index}" pos="{x} {y} 0" euler="0 0 {yaw_deg}">
      <geom type="cylinder" pos="{-_SIGN_THICKNESS_M - _POLE_RADIUS_M} 0 {z / 2}" size="{_POLE_RADIUS_M} {z / 2}" rgba="0.55 0.55 0.58 1"/>
      <geom type="mesh" mesh="yield_border" pos="0 0 {z}" rgba="0.80 0.05 0.06 1"/>
      <geom type="mesh" mesh="yield_face" pos="0.001 0 {z - 0.004}" rgba="0.97 0.97 0.97 1" contype="0" conaffinity="0"/>
    </body>"""


def _walls_xml() -> str:
    x0, x1, y0, y1 = map_facts.WALL_BOUNDS_M
    h, t = map_facts.WALL_HEIGHT_M, 0.02
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    hx, hy = (x1 - x0) / 2 + t, (y1 - y0) / 2 + t
    walls = [("north", cx, y1 + t / 2, hx, t / 2), ("south", cx, y0 - t / 2, hx, t / 2),
             ("east", x1 + t / 2, cy, t / 2, hy), ("west", x0 - t / 2, cy, t / 2, hy)]
    return "".join(
        f'\n    <geom name="wall_{n}" type="box" pos="{x} {y} {h / 2}" size="{sx} {sy} {h / 2}" rgba="0.82 0.82 0.80 1"/>'
        for n, x, y, sx, sy in walls)


def _room_xml(cx: float, cy: float) -> str:
    """The lab around the mat: far walls and a ceiling, cheaper to render than a skybox."""
    half, height = 6.0, 3.0
    boxes = [(cx, cy + half, half, 0.05), (cx, cy - half, half, 0.05),
             (cx + half, cy, 0.05, half), (cx - half, cy, 0.05, half)]
    walls = "".join(
        f'\n    <geom type="box" pos="{x} {y} {height / 2}" size="{sx} {sy} {height / 2}" rgba="0.70 0.71 0.74 1" contype="0" conaffinity="0" group="1"/>'
        for x, y, sx, sy in boxes)
    return walls + (f'\n    <geom type="box" pos="{cx} {cy} {height}" size="{half} {half} 0.05" rgba="0.80 0.80 0.82 1"'
                    ' contype="0" conaffinity="0" group="1"/>')


def _obstacle_xml(index: int, x: float, y: float, yaw: float) -> str:
    lx, ly, h = OBSTACLE_SIZE_M
    return f"""
    <body name="{obstacle_body(index)}" pos="{x} {y} 0" euler="0 0 {math.degrees(yaw)}">
      <geom name="obstacle_{index}" type="box" pos="0 0 {h / 2}" size="{lx / 2} {ly / 2} {h / 2}" rgba="0.16 0.33 0.78 1"/>
    </body>"""


def build_scene_xml(sign_geometry: SignGeometry = PLATE_IN_SCAN, world_xml: str = "") -> str:
    """The full MJCF text of the map with the car (the car's file is an include), the stop
    signs built to ``sign_geometry``, and the bodies the env's world managers add
    (``world_xml``: ``racf.sim.world.manager``; a scenario's props and actors)."""
    x0, x1, y0, y1 = map_facts.WALL_BOUNDS_M
    cx, cy, sx, sy = (x0 + x1) / 2, (y0 + y1) / 2, (x1 - x0) / 2, (y1 - y0) / 2
    props = "".join(_stop_sign_xml(s.index, *s.position, s.face_yaw, s.geometry) for s in stop_signs(sign_geometry))
    props += "".join(_traffic_light_xml(i, *p) for i, p in enumerate(map_facts.TRAFFIC_LIGHTS))
    props += "".join(_yield_sign_xml(i, *p) for i, p in enumerate(map_facts.YIELD_SIGNS))
    props += "".join(_obstacle_xml(o.index, *o.body_centre, o.yaw) for o in obstacles())
    props += world_xml
    w, h = MAX_IMAGE_SIZE
    # numstacks: a cylinder's side is straight, so it needs no stacks along its axis, and the
    # scene has no spheres or capsules (which would). With MuJoCo's default of 16, the poles
    # and lamps took a third of a software-rendered frame; 2 changes about one pixel a frame.
    return f"""<mujoco model="qcar2_sdcs_map">
  <compiler angle="degree" autolimits="true"/>
  <option timestep="0.002" integrator="implicitfast" cone="elliptic"/>
  <visual>
    <global offwidth="{w}" offheight="{h}"/>
    <quality shadowsize="0" offsamples="0" numstacks="2"/>
    <map znear="0.01" zfar="50"/>
    <headlight ambient="0.45 0.45 0.45" diffuse="0.35 0.35 0.35" specular="0 0 0"/>
  </visual>
  <default>
    <!-- World geoms collide with wheels (bit 1) and with the car's chassis (bit 2). -->
    <geom conaffinity="3"/>
  </default>
  <statistic extent="6" center="{cx} {cy} 0"/>
  <asset>
    <texture name="mat" type="2d" file="mat.png"/>
    <material name="mat" texture="mat" texrepeat="1 1" texuniform="false" specular="0" shininess="0" reflectance="0"/>
    <material name="lab_floor" rgba="0.45 0.45 0.47 1" specular="0" reflectance="0"/>
    {_octagon_mesh("stop_octagon_border", SIGN_FACE_ACROSS_FLATS_M, _SIGN_THICKNESS_M)}
    {_octagon_mesh("stop_octagon_face", SIGN_RED_FACE_ACROSS_FLATS_M, 0.0005)}
    {_triangle_mesh("yield_border", 0.11, _SIGN_THICKNESS_M)}
    {_triangle_mesh("yield_face", 0.075, 0.0005)}{_patch_assets()}
  </asset>
  <include file="qcar2.xml"/>
  <worldbody>
    <light name="ceiling" pos="{cx} {cy} 4" dir="0 0 -1" diffuse="0.5 0.5 0.5" castshadow="false"/>
    <geom name="lab_floor" type="plane" pos="{cx} {cy} -0.002" size="12 12 4" material="lab_floor" contype="0" conaffinity="0"/>
    <geom name="mat" type="plane" pos="{cx} {cy} 0" size="{sx} {sy} 0.5" material="mat" friction="0.75 0.005 0.0001"/>{_walls_xml()}{_room_xml(cx, cy)}{props}
  </worldbody>
</mujoco>
"""


@lru_cache(maxsize=8)
def _compiled_xml_and_assets(sign_geometry: SignGeometry, world_xml: str) -> tuple[str, tuple[tuple[str, bytes], ...]]:
    car = (ASSETS_DIR / "qcar2.xml").read_bytes()
    return build_scene_xml(sign_geometry, world_xml), (("qcar2.xml", car), ("mat.png", mat_png_bytes()))


def car_xml() -> bytes:
    """The QCar 2's MJCF (a scenario that adds other cars copies their bodies from it)."""
    return (ASSETS_DIR / "qcar2.xml").read_bytes()


def load_model(sign_geometry: SignGeometry = PLATE_IN_SCAN, world_xml: str = "") -> mujoco.MjModel:
    """Compiles a fresh ``MjModel`` of the map with the car (each caller gets its own copy),
    the stop signs built to ``sign_geometry`` and the bodies of ``world_xml`` (the world
    managers'; the MJCF text is cached per geometry and world)."""
    if not isinstance(sign_geometry, SignGeometry):
        raise TypeError(f"sign_geometry must be a SignGeometry, got {type(sign_geometry).__name__}")
    xml, assets = _compiled_xml_and_assets(sign_geometry, world_xml)
    return mujoco.MjModel.from_xml_string(xml, assets=dict(assets))
