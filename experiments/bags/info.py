"""``racf bag-info``: a bag's topics, types, counts, rates and duration."""

from __future__ import annotations

from pathlib import Path

from racf.experiments.bags.recording import custom_data, messages, open_reader

__all__ = ["bag_info"]


def bag_info(path: str | Path) -> dict:
    """The bag at ``path`` in numbers: per topic its type, message count and mean rate over the span
    of its own messages (log time; None for a topic with one message), and the bag's duration."""
    reader = open_reader(path)
    try:
        first: dict[str, int] = {}
        last: dict[str, int] = {}
        for conn, t_ns, _ in messages(reader, path):
            first.setdefault(conn.topic, t_ns)
            last[conn.topic] = t_ns
        topics = []
        for conn in sorted(reader.connections, key=lambda c: c.topic):
            count = conn.msgcount
            span = (last.get(conn.topic, 0) - first.get(conn.topic, 0)) / 1e9
            rate = (count - 1) / span if count > 1 and span > 0 else None
            topics.append({"topic": conn.topic, "type": conn.msgtype, "count": count, "rate_hz": rate})
        custom = custom_data(reader)
        duration = (reader.end_time - reader.start_time - 1) / 1e9 if reader.message_count else 0.0
        storage = "mcap" if any(Path(path).glob("*.mcap")) else "sqlite3" if any(Path(path).glob("*.db3")) else "?"
        return {"path": str(path), "storage": storage, "messages": reader.message_count,
                "start_ns": reader.start_time if reader.message_count else None, "duration_s": duration,
                "trial_id": custom.get("racf.trial_id"), "topics": topics}
    finally:
        reader.close()
