"""Where world managers were first documented: :mod:`racf.sim.world.manager` holds them now (the
world's own floor, so that managers in ``racf.sim.world`` need not import the env). Kept so that a
user's ``from racf.sim.env.world import WorldManager`` goes on working."""

from racf.sim.world.manager import TruthColumn, WorldManager

__all__ = ["WorldManager", "TruthColumn"]
