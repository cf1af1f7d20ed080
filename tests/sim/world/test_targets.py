"""A declared target: its kind is one racf knows, its pose comes from its own truth columns, and a
world's targets of one kind are found in the managers' order."""

from __future__ import annotations

import math

import numpy as np

import pytest

from racf.sim.world.lead_manager import LeadManager
from racf.sim.world.manager import QCAR2_BOX_M, TARGET_KINDS, WorldManager, WorldTarget, world_targets
from racf.sim.world.qcar2_body import QCar2Body


def test_a_target_of_an_unknown_kind_or_shape_is_refused():
    with pytest.raises(ValueError, match="kind must be one of"):
        WorldTarget("bike", "cyclist", "bike_0", ("bx", "by", "byaw"), QCAR2_BOX_M)
    with pytest.raises(ValueError, match="pose_columns names x, y, yaw"):
        WorldTarget("bike", "vehicle", "bike_0", ("bx", "by"), QCAR2_BOX_M)
    assert set(TARGET_KINDS) == {"vehicle", "sign", "obstacle", "person"}


def test_its_pose_is_read_from_its_own_columns_and_none_while_it_is_away():
    target = QCar2Body("van").target(("van_x", "van_y", "van_yaw"))
    assert target.pose({"van_x": 1.0, "van_y": 2.0, "van_yaw": 0.5, "lead_x": 9.0}) == (1.0, 2.0, 0.5)
    assert target.pose({"van_x": math.nan, "van_y": 2.0, "van_yaw": 0.5}) is None and target.pose({}) is None
    assert (target.kind, target.body, target.size_m) == ("vehicle", "van_0", QCAR2_BOX_M)


class _Walker(WorldManager):
    def targets(self):
        return (WorldTarget("walker", "person", "walker", ("wx", "wy", "wyaw"), (0.04, 0.04, 0.18)),)


def test_a_world_s_targets_of_a_kind_come_in_the_managers_order():
    world = (_Walker(), LeadManager(), WorldManager())
    assert [t.name for t in world_targets(world)] == ["walker", "lead"]
    assert [t.name for t in world_targets(world, "vehicle")] == ["lead"] and world_targets(world, "sign") == ()
    assert LeadManager().targets()[0].pose_columns == tuple(c.name for c in LeadManager().columns()[:3])


def test_a_declared_target_cannot_be_changed():
    import dataclasses

    target = QCar2Body("van").target(("van_x", "van_y", "van_yaw"))
    with pytest.raises(dataclasses.FrozenInstanceError):
        target.kind = "person"


def test_a_qcar2_body_is_placed_where_it_is_told_and_parked_out_of_sight():
    import mujoco

    from racf.sim.world.scene import load_model

    model = load_model(world_xml=QCar2Body("van").xml())
    car = QCar2Body("van")
    car.bind(model)
    data = mujoco.MjData(model)
    car.place(data, 1.5, -0.5, math.pi / 2)
    mujoco.mj_forward(model, data)
    assert np.allclose(data.xpos[car.body], (1.5, -0.5, 0.0), atol=1e-9)
    assert np.allclose(data.xmat[car.body].reshape(3, 3)[:, 0], (0.0, 1.0, 0.0), atol=1e-9)  # heading +y
    car.park(data)
    mujoco.mj_forward(model, data)
    assert data.xpos[car.body][2] < -1.0 and np.allclose(data.xmat[car.body].reshape(3, 3), np.eye(3))
    assert car.owns(car.body) and not car.owns(0)
