"""A declared target: its kind is one racf knows, its pose comes from its own truth columns, and a
world's targets of one kind are found in the managers' order."""

from __future__ import annotations

import math

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
