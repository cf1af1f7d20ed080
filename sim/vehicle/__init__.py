"""The QCar 2 as a MuJoCo physics model: actuation, state read-out and its build (the mounts its software is calibrated with)."""

from racf.sim.vehicle.calibration import CarBuild, car_build
from racf.sim.vehicle.qcar2 import QCar2, VehicleConfig, VehicleState

__all__ = ["CarBuild", "QCar2", "VehicleConfig", "VehicleState", "car_build"]
