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

import lazy_loader

# Each name is imported on first use (SPEC 1): a command's --help never waits for the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "base": ["AttackWrapper"],
    "confidence_degradation": ["ConfidenceDegradation"],
    "depth_bias": ["DepthBias"],
    "depth_blackout": ["DepthBlackout"],
    "frustum_spoof": ["FrustumSpoof"],
    "lidar_dropout": ["LidarDropout"],
    "lidar_spoof": ["LidarSpoof"],
    "link": ["LinkDelay", "LinkDrop", "LinkSpoof"],
    "patch_occlusion": ["PatchOcclusion", "paste_occluder", "patch_rows"],
    "physical_patch": ["PhysicalPatch"],
    "schedule": ["AttackSchedule"],
    "stale": ["StaleData"],
    "stealth_ramp": ["StealthRamp"],
    "timed_dropout": ["TimedDropout"],
})
from racf.plugins import ATTACKS  # noqa: E402  (every attack wrapper by name, plug-ins included)

__all__ += ["ATTACKS"]
