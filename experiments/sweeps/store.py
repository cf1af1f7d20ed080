"""Results that survive a crash and say what made them: the store, the atomic writer and the code version.

:class:`ResultStore` keeps one Parquet part file per finished episode: ``<out>/parts/<id>.parquet``
holds the episode's result row, and ``<out>/<logs_dir>/`` its per-step log when asked for. A
part is written to a temporary name and renamed (:func:`atomic_write`), so a killed run leaves
only whole parts, and a restarted one skips every episode whose part exists. Episode ids are
content hashes of the spec, the configs and :func:`code_version`: a part written by other code
is never mistaken for this code's.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
from functools import lru_cache
from pathlib import Path
from typing import Callable

import pandas as pd

__all__ = ["ResultStore", "atomic_write", "code_version", "source_version"]

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


def atomic_write(path: str | Path, data: str | bytes | pd.DataFrame | Callable[[Path], None]) -> Path:
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
        elif isinstance(data, pd.DataFrame):
            data.to_parquet(tmp, index=False)
        elif callable(data):
            data(tmp)
        else:
            raise TypeError(f"atomic_write takes str, bytes, a DataFrame or a writer function, got {type(data)}")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


class ResultStore:
    """One folder of finished episodes.

    Args:
        out: the folder.
        logs_dir: the sub-folder of per-step logs (and rerun recordings): ``logs`` for sweeps,
            ``trials`` for ``racf trials`` batches.
    """

    def __init__(self, out: str | Path, logs_dir: str = "logs") -> None:
        self.out = Path(out)
        self.parts = self.out / "parts"
        self.logs = self.out / logs_dir

    def prepare(self, spec_text: str | None = None, spec_hash: str | None = None) -> None:
        """Creates the folders; with a spec, records it and refuses a folder that holds another sweep."""
        self.parts.mkdir(parents=True, exist_ok=True)
        if spec_hash is None:
            return
        manifest = self.out / "sweep.json"
        if manifest.exists():
            old = json.loads(manifest.read_text()).get("spec_hash")
            if old != spec_hash:
                raise ValueError(f"{self.out} holds another sweep (spec {old}, this one {spec_hash}); "
                                 "choose another --out")
        else:
            atomic_write(self.out / "spec.toml", spec_text or "")
            atomic_write(manifest, json.dumps({"spec_hash": spec_hash}, indent=1))

    def done_ids(self) -> set[str]:
        return {p.stem for p in self.parts.glob("*.parquet")} if self.parts.exists() else set()

    def log_path(self, episode_id: str, suffix: str = ".parquet") -> Path:
        """Where an episode's per-step log (``.parquet``) or recording (``.rrd``) lives."""
        return self.logs / f"{episode_id}{suffix}"

    def write(self, episode_id: str, row: dict, log: pd.DataFrame | None = None) -> None:
        """Writes one episode (log first, then its row: a row marks a finished episode)."""
        if log is not None:
            self.logs.mkdir(parents=True, exist_ok=True)
            atomic_write(self.log_path(episode_id), log)
        self.parts.mkdir(parents=True, exist_ok=True)
        atomic_write(self.parts / f"{episode_id}.parquet", pd.DataFrame([row]))

    def rows(self, ids: list[str] | None = None) -> pd.DataFrame:
        """Finished episodes' rows: all of them sorted by id (the order never depends on timing),
        or those of ``ids`` in that order (KeyError names a missing one)."""
        if ids is not None:
            missing = [i for i in ids if not (self.parts / f"{i}.parquet").exists()]
            if missing:
                raise KeyError(f"{self.out} has no result for {missing[:3]}{' ...' if len(missing) > 3 else ''}")
            files = [self.parts / f"{i}.parquet" for i in ids]
        else:
            files = sorted(self.parts.glob("*.parquet")) if self.parts.exists() else []
        if not files:
            return pd.DataFrame()
        frame = pd.concat([pd.read_parquet(f) for f in files], ignore_index=True)
        return frame if ids is not None else frame.sort_values("trial_id", ignore_index=True)
