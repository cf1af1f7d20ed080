"""Every attack wrapper by name, plug-ins included: :data:`racf.plugins.ATTACKS`, under the name
this package has always given it."""

from racf.plugins import ATTACKS

__all__ = ["ATTACKS"]
