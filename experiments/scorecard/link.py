"""The services a battery's link rows are served by: ``racf serve`` processes the card starts itself,
one on a plain link and one on CurveZMQ (its keys made once in the card's folder and kept, so that a
resumed card talks to a service with the same keys)."""

from __future__ import annotations

from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Iterator

__all__ = ["link_services", "LINKS"]

LINKS = ("plain", "curve")


@contextmanager
def link_services(defence: str, options: dict | None, links: set[str], out: Path) -> Iterator[dict[str, dict]]:
    """For each of ``links``, a running service of ``defence`` and the spec fields that reach it."""
    from racf.experiments.link.curve import make_keys
    from racf.experiments.sweeps.service_process import service_process

    unknown = sorted(set(links) - set(LINKS))
    if unknown:
        raise ValueError(f"a battery row's link must be one of {LINKS}, got {unknown[0]!r}")
    fields: dict[str, dict] = {}
    with ExitStack() as stack:
        for link in sorted(links):
            keys = None
            if link == "curve":
                keys = Path(out) / "link-keys"
                if not (keys / "server.key_secret").exists():
                    make_keys(keys)
            endpoint, _ = stack.enter_context(service_process(defence, options, keys=keys))
            fields[link] = {"estimator_endpoint": endpoint, "estimator_keys": None if keys is None else str(keys)}
        yield fields
