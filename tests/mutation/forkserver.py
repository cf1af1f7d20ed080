"""A warm process for `make mutate`'s test runs: it imports once what racf imports (torch, pandas,
scikit-learn, MuJoCo, ZeroMQ, pytest: about 3 s a run otherwise), never racf itself, and forks a
child per mutant that imports racf from disk, mutant included, and runs the mutant's tests.

    python tests/mutation/forkserver.py SOCKET     # serves until its socket file is removed

A request is one line of JSON, {"tests": [...], "module": "experiments/..."}; the answer one line,
{"rc": pytest's exit code, "last": its last line of output}.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def third_party() -> list[str]:
    """The top-level modules importing racf's link and episode code loads, racf's own left out (read in
    a process of its own, so that this one never holds racf)."""
    probe = ("import sys, racf.experiments.episode, racf.experiments.link.remote, racf.experiments.service.server, "
             "racf.experiments.cli, pytest, hypothesis, xdist; "
             "print('\\n'.join(sorted({m.split('.')[0] for m in sys.modules})))")
    out = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return [m for m in out.split() if m not in ("racf", "tests", "__main__") and not m.startswith("_")]


def warm() -> None:
    import importlib

    for name in third_party():
        try:
            importlib.import_module(name)
        except Exception:  # noqa: BLE001 - a module that cannot be imported alone is imported by its user
            pass
    assert not any(m == "racf" or m.startswith("racf.") for m in sys.modules), "the warm process holds racf"


def run(request: dict) -> dict:
    """Forks a child that runs pytest on the request's tests; its exit code and last line."""
    with tempfile.TemporaryFile("w+") as out:
        pid = os.fork()
        if pid == 0:  # the child: racf is imported here, from disk, the mutant with it
            try:
                os.dup2(out.fileno(), 1)
                os.dup2(out.fileno(), 2)
                import pytest

                from run_tests import PYTEST_ARGS

                code = pytest.main([*PYTEST_ARGS, *request["tests"]])
            except BaseException:  # noqa: BLE001 - whatever happens, the child ends here
                code = 3
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(int(code))
        _, status = os.waitpid(pid, 0)
        out.seek(0)
        lines = out.read().strip().splitlines()
    return {"rc": os.waitstatus_to_exitcode(status), "last": lines[-1] if lines else ""}


def main(path: str) -> int:
    os.chdir(ROOT)
    sys.path[:0] = [str(ROOT), str(Path(__file__).resolve().parent)]
    warm()
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(path)
    server.listen(1)
    server.settimeout(1.0)
    print("ready", flush=True)
    while os.path.exists(path):
        try:
            conn, _ = server.accept()
        except socket.timeout:
            continue
        with conn, conn.makefile("rw") as stream:
            answer = run(json.loads(stream.readline()))
            stream.write(json.dumps(answer) + "\n")
            stream.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
