"""The files racf needs at run time: the car's MJCF and the indoor map (``qcar2_map/``), the
shipped checkpoints (``checkpoints/``) and the printed stickers (``patches/``).

They install inside the package (``racf.assets``), so an installed racf finds them with
:func:`importlib.resources.files` wherever it lives; nothing reads the repository's layout.
"""

from __future__ import annotations

import os
from importlib.resources import files
from pathlib import Path

__all__ = ["asset_path"]


def asset_path(*parts: str) -> Path:
    """The path of a shipped asset, e.g. ``asset_path("checkpoints", "odca-head")``.

    MuJoCo and torch open files by path, so the asset must be a real file on disk (it is, in a
    wheel installed by pip or in a checkout); FileNotFoundError names what is missing.
    """
    path = Path(os.fspath(files(__name__).joinpath(*parts)))
    if not path.exists():
        raise FileNotFoundError(f"racf asset {'/'.join(parts)!r} is missing from {path.parent} "
                                f"(reinstall racf: the wheel carries its assets)")
    return path
