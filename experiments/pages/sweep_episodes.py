"""A sweep folder's episodes as this code makes them: the one reader of ``parts/`` for the pages.

A sweep's folder keeps the parts of every code that ran it (a part's name carries its code's
identity, so a resumed run never reuses a stale one). A page that summarises the folder counts only
the episodes its spec makes with this code; a part left from older code is not one of them.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

__all__ = ["current_episodes"]


def current_episodes(folder: Path) -> tuple[pd.DataFrame, dict]:
    """The folder's episode rows this code made, and its spec's episodes by trial id (empty without a
    ``spec.toml``, or with an empty one: then every part is taken). ValueError, naming what to do, where none are."""
    folder = Path(folder)
    parts = sorted((folder / "parts").glob("*.parquet"))
    if not parts:
        raise ValueError(f"{folder} holds no episodes (parts/*.parquet): give a sweep's output folder")
    frame = pd.concat([pd.read_parquet(p) for p in parts], ignore_index=True)
    specs: dict = {}
    spec = (folder / "spec.toml").read_text() if (folder / "spec.toml").exists() else ""
    if spec.strip():
        from racf.experiments.sweeps.spec import parse_spec

        specs = {s.trial_id: s for s in parse_spec(spec).episodes()}
        frame = frame[frame["trial_id"].isin(specs)].drop_duplicates("trial_id")
        if frame.empty:
            raise ValueError(f"{folder}'s episodes were run by other code; run its sweep again")
    return frame.reset_index(drop=True), specs
