"""racf: a simulation-first testbed for resilient stop-sign distance perception on the Quanser QCar 2.

The distribution installs one namespace:

- :mod:`racf.sim`: the MuJoCo world, the car, its sensors, the Gymnasium env and the attack wrappers;
- :mod:`racf.controllers`: the car's software (detectors, perception, estimators, braking, steering);
- :mod:`racf.odca`: the Object Distance Correction Algorithm (gate, prior, delta head);
- :mod:`racf.experiments`: episodes, sweeps, the offline benchmark, figures and the ``racf`` CLI;
- :mod:`racf.assets`: the map, the car's MJCF and the shipped checkpoints;
- :mod:`racf.plugins`: the registries of estimators, attacks and detectors, filled from entry points.

Importing ``racf`` alone loads nothing heavy; ``import racf.sim`` registers the env.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("racf")
except PackageNotFoundError:  # a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
