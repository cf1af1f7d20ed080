"""Results that survive a crash: the store of finished episodes (what made them: :mod:`racf.provenance`).

:class:`ResultStore` keeps one Parquet part file per finished episode: ``<out>/parts/<id>.parquet``
holds the episode's result row, and ``<out>/<logs_dir>/`` its per-step log when asked for. A
part is written to a temporary name and renamed (:func:`atomic_write`), so a killed run leaves
only whole parts, and a restarted one skips every episode whose part exists. Episode ids are
content hashes of the spec, the configs and :func:`code_version`: a part written by other code
is never mistaken for this code's.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from racf.provenance import atomic_write

__all__ = ["ResultStore"]


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
