"""Attack wrappers for the racf env, one per module; they compose.

- :class:`PatchOcclusion` (``patch_occlusion``): a naturalistic occluder pasted over a share of the sign (RGB).
- :class:`PhysicalPatch` (``physical_patch``): a sticker printed on the sign in the scene (the renderer shows it).
- :class:`DepthBlackout`, :class:`DepthBias`, :class:`ConfidenceDegradation`: depth attacks.
- :class:`LidarDropout`, :class:`LidarSpoof`: LiDAR faults (beyond the paper).
- :class:`StaleData` (``delay``): old data replayed as new: LiDAR scans late, or depth frozen.
- :class:`TimedDropout` (``dropout_timed``): a depth attack on while the LiDAR has nothing on the sign.
- :class:`StealthRamp` (``stealth_ramp``, white box): a depth bias ramp kept under the defence's tolerance.
- :class:`FrustumSpoof` (``frustum_spoof``, white box): the same ramp on depth and LiDAR together.
- :class:`LinkDelay`, :class:`LinkDrop`, :class:`LinkSpoof` (``link_*``): a man in the middle of the
  link to a defence service (``racf serve``): answers late, lost or replaced.
Each marks ``info["attack"]`` (active attacks) and ``info["attack_active"]``.

``ATTACKS`` finds them by name (each wrapper's ``name``). It is :data:`racf.plugins.ATTACKS`,
filled from the ``racf.attacks`` entry points: racf's own are listed in ``pyproject.toml``, and
a user's register the same way (or come from a ``--plugin`` file). Attacks take the registry's
order (racf's own by name, then plug-ins by name) in a setting's name.
"""

from typing import TYPE_CHECKING

import lazy_loader

# Each name is imported on first use (SPEC 1), as __init__.pyi lists them: importing the package costs
# nothing, so the command line's help never waits for torch, scikit-learn or the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

if TYPE_CHECKING:  # the same names for editors that read no stub (jedi); a test holds the two lists equal
    from .base import AttackWrapper
    from .confidence_degradation import ConfidenceDegradation
    from .depth_bias import DepthBias
    from .depth_blackout import DepthBlackout
    from .frustum_spoof import FrustumSpoof
    from .lidar_dropout import LidarDropout
    from .lidar_spoof import LidarSpoof
    from .link import LinkDelay, LinkDrop, LinkSpoof
    from .patch_occlusion import PatchOcclusion, paste_occluder, patch_rows
    from .physical_patch import PhysicalPatch
    from .registry import ATTACKS
    from .schedule import AttackSchedule
    from .stale import StaleData
    from .stealth_ramp import StealthRamp
    from .timed_dropout import TimedDropout
