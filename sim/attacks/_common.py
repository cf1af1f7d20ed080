"""Argument checks shared by the depth and LiDAR attacks."""

from __future__ import annotations

REGIONS = ("sign", "frame")


def check_region(region: str) -> str:
    if region not in REGIONS:
        raise ValueError(f"region must be one of {REGIONS}, got {region!r}")
    return region
