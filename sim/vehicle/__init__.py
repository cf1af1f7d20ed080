"""The QCar 2 as a MuJoCo physics model: actuation and state read-out (its build, the mounts its
software is calibrated with, is the sensors': ``racf.sim.sensors.calibration``)."""

from racf.sim.vehicle.qcar2 import QCar2, VehicleConfig, VehicleState

__all__ = ["QCar2", "VehicleConfig", "VehicleState"]
