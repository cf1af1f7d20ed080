"""The sweep's result store: one Parquet part file per finished episode, written at once.

``<out>/parts/<episode_id>.parquet`` holds the episode's result row; ``<out>/logs/`` its
per-step log when asked for. A part is written to a temporary name and renamed, so a killed
sweep leaves only whole parts, and a restarted one skips every episode whose part exists.
Episode ids are the trials' content hashes (spec, configs, code version): a part written by
other code is never mistaken for this code's.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pandas as pd

__all__ = ["ResultStore"]


class ResultStore:
    def __init__(self, out: str | Path) -> None:
        self.out = Path(out)
        self.parts = self.out / "parts"
        self.logs = self.out / "logs"

    def prepare(self, spec_text: str, spec_hash: str) -> None:
        """Creates the folders and records the spec (refusing a folder that holds another sweep)."""
        self.parts.mkdir(parents=True, exist_ok=True)
        manifest = self.out / "sweep.json"
        if manifest.exists():
            old = json.loads(manifest.read_text()).get("spec_hash")
            if old != spec_hash:
                raise ValueError(f"{self.out} holds another sweep (spec {old}, this one {spec_hash}); "
                                 "choose another --out")
        else:
            manifest.write_text(json.dumps({"spec_hash": spec_hash}, indent=1))
            (self.out / "spec.toml").write_text(spec_text)

    def done_ids(self) -> set[str]:
        return {p.stem for p in self.parts.glob("*.parquet")} if self.parts.exists() else set()

    def write(self, episode_id: str, row: dict, log: pd.DataFrame | None = None) -> None:
        """Writes one episode (log first, then its row: a row marks a finished episode)."""
        if log is not None:
            self.logs.mkdir(parents=True, exist_ok=True)
            _atomic_parquet(log, self.logs / f"{episode_id}.parquet")
        self.parts.mkdir(parents=True, exist_ok=True)
        _atomic_parquet(pd.DataFrame([row]), self.parts / f"{episode_id}.parquet")

    def rows(self) -> pd.DataFrame:
        """Every finished episode's row (sorted by episode id, so the order never depends on timing)."""
        files = sorted(self.parts.glob("*.parquet")) if self.parts.exists() else []
        if not files:
            return pd.DataFrame()
        return pd.concat([pd.read_parquet(f) for f in files], ignore_index=True).sort_values(
            "trial_id", ignore_index=True)


def _atomic_parquet(frame: pd.DataFrame, path: Path) -> None:
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp")
    frame.to_parquet(tmp, index=False)
    os.replace(tmp, path)
