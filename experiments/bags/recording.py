"""A recording opened for replay: its topics checked, its spec found, its messages grouped into
the car's 50 Hz steps.

A message belongs to the first step at or after its log time (when the recorder received it):
in a bag racf wrote, exactly the step whose observation first held it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

from racf.errors import UserError
from racf.experiments.bags.mapping import Mapping
from racf.experiments.bags.topics import (REQUIRED, SCAN_DELIVERED, SCAN_TIMES, SIGN_MASK, SPEC_KEY, TRUTH_PREFIX,
                                          typestore)
from racf.experiments.episode.spec import TrialSpec

__all__ = ["Recording", "open_reader", "custom_data", "STREAM_WHAT"]

#: What each required stream is, for the one line that names a missing one.
STREAM_WHAT = {"rgb": "the colour camera", "depth": "the depth camera", "scan": "the LiDAR", "imu": "the IMU",
               "joint": "the motor encoder", "fix": "the localiser's fix"}


def custom_data(reader) -> dict[str, str]:
    """The bag's ``custom_data`` (rosbag2 metadata v6+; rosbags keeps it on the folder reader)."""
    metadata = getattr(getattr(reader, "storage", None), "metadata", None)
    return dict(getattr(metadata, "custom", None) or {})


def open_reader(path: str | Path):
    """rosbags' reader on a bag folder (or a lone ``.mcap``/``.db3`` file's folder); UserError if
    it is not a bag."""
    from rosbags.rosbag2 import Reader

    path = Path(path)
    if not path.exists():
        raise UserError(f"bag {path} does not exist")
    if path.is_file():
        raise UserError(f"{path} is a file; a rosbag2 is the folder holding metadata.yaml and the .mcap or .db3 file")
    if not (path / "metadata.yaml").exists():
        raise UserError(f"{path} is not a readable rosbag2: it holds no metadata.yaml (a bag folder does)")
    try:
        reader = Reader(path)
        reader.open()
    except Exception as err:  # rosbags, its storage plug-ins and their decompressors raise many kinds
        raise UserError(f"{path} is not a readable rosbag2 ({_words(err)}); {_ADVICE}") from None
    return reader


#: What to do about a bag that cannot be read.
_ADVICE = ("the recording is truncated or corrupt: copy it again from where it was recorded, or re-record it "
           "(`racf bag export` writes one from an episode)")


def _words(err: Exception) -> str:
    return f"{type(err).__name__}: {err}" if str(err) else type(err).__name__


def messages(reader, path: str | Path, **kwargs) -> Iterator[tuple]:
    """``reader.messages(**kwargs)``, with whatever a damaged file raises midway (a bad chunk, a
    failed decompression, a cut-off record) as one UserError naming the bag and where it broke."""
    count = 0
    stream = reader.messages(**kwargs)
    while True:
        try:
            item = next(stream)
        except StopIteration:
            return
        except Exception as err:  # the storage's own errors are of many kinds: one line, whatever broke
            raise UserError(f"bag {path} breaks after {count} readable messages ({_words(err)}); {_ADVICE}") from None
        count += 1
        yield item


@dataclass
class Recording:
    """An open bag and how its streams reach the car."""

    path: Path
    mapping: Mapping
    spec: TrialSpec
    written_by_racf: bool
    topics: frozenset[str] = frozenset()

    @classmethod
    def open(cls, path: str | Path, mapping: Mapping | None = None) -> "Recording":
        """Opens ``path``; fails in one line, before any work, on a missing required topic or a bag
        with neither racf's spec nor a ``[mission]`` in the mapping."""
        mapping = mapping or Mapping()
        reader = open_reader(path)
        try:
            topics = set(reader.topics)
            for stream in REQUIRED:
                topic = mapping.topics[stream]
                if topic not in topics:
                    raise UserError(f"bag {path} has no topic {topic} ({STREAM_WHAT[stream]}, stream '{stream}'); "
                                    f"map another with [topics] {stream} = \"...\" in a mapping file (--mapping); "
                                    f"the bag's topics: {', '.join(sorted(topics))}")
            raw = custom_data(reader).get(SPEC_KEY)
        finally:
            reader.close()
        spec = _spec(raw, mapping, path)
        return cls(Path(path), mapping, spec, raw is not None, frozenset(topics))

    def steps(self, step_ns: int) -> Iterator[tuple[int, dict[str, list]]]:
        """(step, {topic: [decoded messages]}) for every ``step_ns`` from the bag's first message to
        its last, the messages received since the previous step (most steps have some)."""
        reader = open_reader(self.path)
        store = typestore()
        wanted = set(self.mapping.topics.values()) | {SCAN_TIMES, SCAN_DELIVERED, SIGN_MASK,
                                                       "/racf/scan/delivered_times", "/racf/attack_active"}
        try:
            conns = [c for c in reader.connections if c.topic in wanted or c.topic.startswith(TRUTH_PREFIX)]
            t0 = reader.start_time
            k, pending = 0, {}
            for conn, t_ns, raw in messages(reader, self.path, connections=conns):
                while t_ns > t0 + k * step_ns:
                    yield k, pending
                    k, pending = k + 1, {}
                pending.setdefault(conn.topic, []).append(store.deserialize_cdr(raw, conn.msgtype))
            yield k, pending
        finally:
            reader.close()


def _spec(raw: str | None, mapping: Mapping, path) -> TrialSpec:
    """The bag's own spec (racf wrote it), overridden by the mapping's ``[mission]``; or the mission
    alone, with racf's defaults for the rest."""
    fields = json.loads(raw) if raw is not None else {"setting": "clean", "sign": 0, "speed": 1.0, "seed": 0}
    if raw is None and not mapping.mission:
        raise UserError(f"bag {path} was not written by racf: give its mission (the target, the speed) in a mapping "
                        "file's [mission] table, e.g. sign = 2 and speed = 1.0 (--mapping)")
    fields.update(mapping.mission)
    try:
        return TrialSpec.from_dict(fields)
    except (TypeError, ValueError) as err:
        raise UserError(f"the recording's mission {mapping.mission or '(from the bag)'}: {err}") from None
