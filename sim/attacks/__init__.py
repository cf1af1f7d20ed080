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

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.confidence_degradation import ConfidenceDegradation
from racf.sim.attacks.depth_bias import DepthBias
from racf.sim.attacks.depth_blackout import DepthBlackout
from racf.sim.attacks.frustum_spoof import FrustumSpoof
from racf.sim.attacks.lidar_dropout import LidarDropout
from racf.sim.attacks.lidar_spoof import LidarSpoof
from racf.sim.attacks.link import LinkDelay, LinkDrop, LinkSpoof
from racf.sim.attacks.patch_occlusion import PatchOcclusion, paste_occluder, patch_rows
from racf.sim.attacks.physical_patch import PhysicalPatch
from racf.sim.attacks.schedule import AttackSchedule
from racf.sim.attacks.stale import StaleData
from racf.sim.attacks.stealth_ramp import StealthRamp
from racf.sim.attacks.timed_dropout import TimedDropout

from racf.plugins import ATTACKS  # noqa: E402  (every attack wrapper by name, plug-ins included)

__all__ = ["ATTACKS", "AttackSchedule", "AttackWrapper", "ConfidenceDegradation", "DepthBias", "DepthBlackout",
           "FrustumSpoof", "LidarDropout", "LidarSpoof", "LinkDelay", "LinkDrop", "LinkSpoof", "PatchOcclusion", "PhysicalPatch", "StaleData", "StealthRamp", "TimedDropout",
           "paste_occluder", "patch_rows"]
