"""The car's stages assembled in its room: a supervisor per published kind, after every publisher; a
stage that publishes no track cannot be supervised; a supervisor that stands in replaces its
publisher's cap, and no other cap."""

import math

import pytest

from racf.experiments.car.assembly import supervisor_classes
from racf.experiments.car.following.stage import FollowingStage
from racf.experiments.car.software import lowest_cap
from racf.experiments.car.stage import CarStage, StageLimit
from racf.experiments.car.supervisor.vehicle import VehicleSupervisor


class Quiet(CarStage):
    name = "quiet"


class Person(CarStage):
    name = "person_stage"
    publishes = "person"


def test_one_supervisor_a_kind_the_car_s_own_first_then_the_stages():
    classes = supervisor_classes([FollowingStage, Person], ("sign", "sign"))
    assert [c.supervises for c in classes] == ["sign", "vehicle", "person"]
    assert classes[1] is VehicleSupervisor and not classes[0].stands_in and classes[1].stands_in


def test_a_stage_that_publishes_no_track_is_named_in_one_line():
    with pytest.raises(ValueError, match="car stage 'quiet' publishes no typed track") as err:
        supervisor_classes([FollowingStage, Quiet], ("sign",))
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match="no supervisor for a target of kind 'balloon'"):
        supervisor_classes([], ("balloon",))


def test_a_supervisor_that_stands_in_replaces_its_publisher_s_cap_and_no_other():
    following, supervisor, person = FollowingStage.__new__(FollowingStage), VehicleSupervisor.__new__(
        VehicleSupervisor), Person.__new__(Person)
    stages = (following, person, supervisor)
    said = [StageLimit(0.0), StageLimit(0.8), StageLimit(1.2)]
    # The following stage's 0 is replaced by the supervisor's 1.2; the person's 0.8 and the braker's 2.0 stand.
    assert lowest_cap(2.0, said, stages) == 0.8
    assert lowest_cap(0.5, said, stages) == 0.5
    # Without the supervisor, the lowest of all, as before.
    assert lowest_cap(2.0, said[:2], stages[:2]) == 0.0 and lowest_cap(math.inf, [], ()) == math.inf


def test_the_stages_are_unsupervised_unless_asked():
    from racf.experiments.car.assembly import car_stages
    from racf.experiments.car.stage import StageContext

    context = StageContext(None, (0.2, 0.0), 0.17, (0.1, 0.0), 0.1, lambda: None, target_decel_mps2=6.0)
    assert car_stages((), context, car_kinds=("sign",)) == ()
    assert [s.supervises for s in car_stages((), context, True, car_kinds=("sign",))] == ["sign"]
