"""A ``racf serve`` process for a batch, a bench or a test: started on a free loopback port, its log
in a file, stopped after."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from contextlib import contextmanager
from typing import Iterator

__all__ = ["service_process"]


@contextmanager
def service_process(defence: str, options: dict | None = None, bind: str = "tcp://127.0.0.1:0",
                    keys=None, flags: tuple[str, ...] = (), python: str | None = None) -> Iterator[tuple]:
    """A ``racf serve`` process for ``defence`` (``keys``: a key folder, CurveZMQ; ``flags``: more of
    ``racf serve``'s; ``python``: another interpreter's racf, to measure another checkout); yields
    (endpoint, process) and stops it after."""
    import json

    cmd = [python or sys.executable, "-m", "racf.experiments.cli", "serve", "--defence", defence, "--bind", bind,
           *flags]
    if keys is not None:
        cmd += ["--keys", str(keys)]
    for key, value in (options or {}).items():
        cmd += ["--estimator-option", f"{key}={json.dumps(value)}"]
    # Its log goes to a file: a pipe nobody reads would fill and stop the service mid-run.
    log = tempfile.TemporaryFile("w+")
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=log, text=True)
    try:
        line = proc.stdout.readline()
        if not line.startswith("listening at "):
            proc.kill()
            proc.wait()
            log.seek(0)
            raise RuntimeError(f"racf serve did not start: {line.strip()} {log.read().strip()[-2000:]}")
        yield line.split("listening at ", 1)[1].split()[0], proc
    finally:
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
        log.close()
