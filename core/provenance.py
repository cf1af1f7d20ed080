"""Provenance: what made a result (the code version, a file's or plug-in's source hash) and
writes that leave a whole file or none; the commit and the machine a stored measurement names.

The floor of racf: it imports nothing of racf's, so every package (``sim``, ``experiments``,
``racf.plugins``) can stand on it. Results are identified by what produced them: a trial id
hashes :func:`code_version` of the episode's code; a plug-in's id hashes :func:`source_version`
of its file, read afresh.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import subprocess
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable

__all__ = ["atomic_write", "code_version", "source_version", "commit", "machine"]

_CODE_SUFFIXES = (".py", ".xml", ".json", ".npz", ".safetensors", ".png", ".bin", ".pt", ".toml")


@lru_cache(maxsize=None)
def code_version(*roots: str) -> str:
    """A hash of the source and assets under ``roots``, cached per process (racf's own code does
    not change under a running process; a user's plug-in is hashed afresh by :func:`source_version`).

    Each root is a dotted module or package name (``racf.sim``, ``racf.experiments.episode``,
    ``racf.assets``: every file under a package's folder) or a filesystem path (a file or a
    folder, e.g. a checkpoint). It changes with any edit, committed or not; file names count
    too, so a moved file changes it. The names hashed are relative to each root, so an editable
    checkout and an installed wheel of the same code agree. Episodes hash
    ``racf.experiments.episode.spec.EPISODE_CODE``.
    """
    return source_version(*roots)


def source_version(*roots: str) -> str:
    """:func:`code_version` without the cache: for sources that may change while a process runs
    (a plug-in a user is editing). ValueError names a root that does not exist."""
    if not roots:
        raise ValueError("code_version needs at least one module, folder or file")
    h = hashlib.sha256()
    for root in roots:
        base = _locate(root)
        h.update(root.encode() if not Path(root).is_absolute() else b"<path>")
        for path in [base] if base.is_file() else sorted(base.rglob("*")):
            if path.is_file() and path.suffix in _CODE_SUFFIXES and "__pycache__" not in path.parts:
                h.update(str(path.relative_to(base)).encode() if path != base else path.name.encode())
                h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _locate(root: str) -> Path:
    """The file or folder a root names: a path that exists, else a module's file or a package's folder."""
    path = Path(root)
    if path.is_absolute() or os.sep in root:
        if not path.exists():
            raise ValueError(f"code_version: no file or folder {root!r}")
        return path.resolve()
    try:
        spec = importlib.util.find_spec(root)
    except (ImportError, ValueError):
        spec = None
    if spec is None:
        raise ValueError(f"code_version: no module or package {root!r}")
    if spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations))).resolve()
    if spec.origin is None or not Path(spec.origin).exists():
        raise ValueError(f"code_version: module {root!r} has no source file")
    return Path(spec.origin).resolve()


def machine() -> str:
    """The machine in words: its CPU cores, and its GPU if torch sees one."""
    try:
        import torch

        gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() else None
    except ImportError:  # torch is a dependency, but the store must not need it
        gpu = None
    return f"{os.cpu_count()} CPU cores, " + (gpu or "no GPU")


def commit(root: Path = Path(".")) -> str:
    """The checkout's short commit, with ``+changes`` when tracked code differs from it."""
    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, check=True).stdout

    try:
        head = git("rev-parse", "--short", "HEAD").strip()
        dirty = git("status", "--porcelain", "--untracked-files=no", "--", "sim", "odca", "controllers",
                    "experiments", "assets", "core").strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return head + ("+changes" if dirty else "")


def atomic_write(path: str | Path, data: str | bytes | Any | Callable[[Path], None]) -> Path:
    """Writes ``path`` whole or not at all: to a temporary name beside it, then renamed.

    ``data`` is text, bytes, a DataFrame (Parquet) or a function that writes a given path
    (e.g. ``lambda p: torch.save(state, p)``). The temporary name carries the process id, so
    workers writing the same folder never share one.
    """
    path = Path(path)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        if isinstance(data, str):
            tmp.write_text(data)
        elif isinstance(data, bytes):
            tmp.write_bytes(data)
        elif hasattr(data, "to_parquet"):  # a DataFrame (pandas stays out of the floor's imports)
            data.to_parquet(tmp, index=False)
        elif callable(data):
            data(tmp)
        else:
            raise TypeError(f"atomic_write takes str, bytes, a DataFrame or a writer function, got {type(data)}")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path
