# The package's names, for type checkers and editors, and for lazy_loader, which imports each on
# first use (racf's __init__.py reads this file): the one list of what the package exports.
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

__all__ = ["ATTACKS", "AttackSchedule", "AttackWrapper", "ConfidenceDegradation", "DepthBias", "DepthBlackout",
           "FrustumSpoof", "LidarDropout", "LidarSpoof", "LinkDelay", "LinkDrop", "LinkSpoof", "PatchOcclusion",
           "PhysicalPatch", "StaleData", "StealthRamp", "TimedDropout", "paste_occluder", "patch_rows"]
