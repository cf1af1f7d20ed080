"""The car's stages assembled in its own room: the mission's stages by name, and, where the settings
ask for runtime assurance, a supervisor above every target the car publishes a track of.

Supervision is a contract (:class:`~racf.experiments.car.stage.TargetTrack`): a stage that defends a
distance says which kind of track it publishes (``CarStage.publishes``), and the car's own loop
publishes its sign's (or crate's). Each published kind gets the supervisor of its kind, after every
publisher: a moving target's (:class:`~racf.experiments.car.supervisor.vehicle.VehicleSupervisor`,
whose cap stands in for its publisher's) or a static one's
(:func:`~racf.experiments.car.supervisor.static.static_supervisor`, which only adds a limit). The
engine names none of them.
"""

from __future__ import annotations

from racf.experiments.car.stage import CarStage, StageContext

__all__ = ["car_stages", "supervisor_classes", "MOVING_KINDS", "STATIC_KINDS"]

#: Kinds of target that move, and that stand (``racf.sim.world.manager.TARGET_KINDS``).
MOVING_KINDS = ("vehicle",)
STATIC_KINDS = ("sign", "obstacle", "person")


def _supervisor_of(kind: str) -> type[CarStage]:
    if kind in MOVING_KINDS:
        from racf.experiments.car.supervisor.vehicle import VehicleSupervisor

        return VehicleSupervisor
    if kind in STATIC_KINDS:
        from racf.experiments.car.supervisor.static import static_supervisor

        return static_supervisor(kind)
    raise ValueError(f"supervisor: no supervisor for a target of kind {kind!r}; allowed: "
                     f"{', '.join(MOVING_KINDS + STATIC_KINDS)}")


def supervisor_classes(stage_classes, car_kinds: tuple[str, ...]) -> tuple[type[CarStage], ...]:
    """The supervisors for these stages' published tracks and the car's own targets' kinds, one per kind.
    ValueError names a stage that publishes no typed track: it cannot be supervised."""
    kinds: list[str] = list(dict.fromkeys(car_kinds))
    for cls in stage_classes:
        if getattr(cls, "supervises", None) is not None:
            continue  # a supervisor engaged by name supervises already
        kind = getattr(cls, "publishes", None)
        if kind is None:
            raise ValueError(f"supervisor: car stage {cls.name!r} publishes no typed track (CarStage.publishes and "
                             f"StageLimit.track), so it cannot be supervised; allowed: the supervisor over stages that "
                             f"publish one ({', '.join(MOVING_KINDS + STATIC_KINDS)})")
        kinds.append(kind)
    return tuple(_supervisor_of(kind) for kind in dict.fromkeys(kinds))


def car_stages(names: tuple[str, ...], context: StageContext, supervised: bool = False,
               car_kinds: tuple[str, ...] = ()) -> tuple[CarStage, ...]:
    """The stages ``names`` engages (``racf.car_stages`` parts), each on the car's build with its own
    defence instance; ``supervised``: then a supervisor above each published track and the car's own
    targets' kinds (``car_kinds``)."""
    from racf.plugins import CAR_STAGES

    classes = [CAR_STAGES[name] for name in names]
    if supervised:
        classes += supervisor_classes(classes, car_kinds)
    return tuple(cls(context) for cls in classes)
