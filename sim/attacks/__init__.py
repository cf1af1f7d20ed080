"""Attack wrappers for the racf env, one per module; they compose.

- :class:`PatchOcclusion` (``patch_occlusion``): a naturalistic occluder pasted over a share of the sign (RGB).
- :class:`PhysicalPatch` (``physical_patch``): a sticker printed on the sign in the scene (the renderer shows it).
- :class:`DepthBlackout`, :class:`DepthBias`, :class:`ConfidenceDegradation`: depth attacks.
- :class:`LidarDropout`, :class:`LidarSpoof`: LiDAR faults (beyond the paper).
- :class:`StaleData` (``delay``): old data replayed as new: LiDAR scans late, or depth frozen.
- :class:`TimedDropout` (``dropout_timed``): a depth attack on while the LiDAR has nothing on the sign.
- :class:`StealthRamp` (``stealth_ramp``, white box): a depth bias ramp kept under the defence's tolerance.
- :class:`FrustumSpoof` (``frustum_spoof``, white box): the same ramp on depth and LiDAR together.
Each marks ``info["attack"]`` (active attacks) and ``info["attack_active"]``.

``ATTACKS`` finds them by name (each wrapper's ``name``): a new attack is one module and one
line there. The order is the order attacks take in a setting's name.
"""

from sim.attacks.base import AttackWrapper
from sim.attacks.confidence_degradation import ConfidenceDegradation
from sim.attacks.depth_bias import DepthBias
from sim.attacks.depth_blackout import DepthBlackout
from sim.attacks.frustum_spoof import FrustumSpoof
from sim.attacks.lidar_dropout import LidarDropout
from sim.attacks.lidar_spoof import LidarSpoof
from sim.attacks.patch_occlusion import PatchOcclusion, paste_occluder, patch_rows
from sim.attacks.physical_patch import PhysicalPatch
from sim.attacks.schedule import AttackSchedule
from sim.attacks.stale import StaleData
from sim.attacks.stealth_ramp import StealthRamp
from sim.attacks.timed_dropout import TimedDropout

#: Every attack wrapper by name.
ATTACKS: dict[str, type[AttackWrapper]] = {cls.name: cls for cls in (
    PatchOcclusion, PhysicalPatch, LidarSpoof, LidarDropout, DepthBlackout, DepthBias, ConfidenceDegradation, StaleData, TimedDropout, StealthRamp, FrustumSpoof)}

__all__ = ["ATTACKS", "AttackSchedule", "AttackWrapper", "ConfidenceDegradation", "DepthBias", "DepthBlackout",
           "FrustumSpoof", "LidarDropout", "LidarSpoof", "PatchOcclusion", "PhysicalPatch", "StaleData", "StealthRamp", "TimedDropout",
           "paste_occluder", "patch_rows"]
