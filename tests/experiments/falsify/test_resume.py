"""A search killed with SIGKILL resumes from its stored trials and episodes, redoing none."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest


@pytest.mark.slow
def test_a_search_killed_mid_run_resumes_without_redoing_episodes(tmp_path):
    out = tmp_path / "search"
    cmd = [sys.executable, "-m", "racf.experiments.cli", "falsify", "--defence", "raw", "--attack", "patch_occlusion",
           "--budget", "8", "--seeds", "1", "--sampler", "random", "--batch", "2", "--workers", "1", "--no-cases",
           "--out", str(out), "--json"]
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    parts = out / "episodes" / "parts"
    deadline = time.time() + 300
    while time.time() < deadline and len(list(parts.glob("*.parquet"))) < 3:
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = {p.name: p.stat().st_mtime_ns for p in parts.glob("*.parquet")}
    assert 3 <= len(before) < 8, "killed mid-search"
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout)
    after = {p.name: p.stat().st_mtime_ns for p in parts.glob("*.parquet")}
    assert all(after[name] == stamp for name, stamp in before.items())  # nothing stored was run again
    assert report["episodes_run"] == len(after) - len(before) and len(after) == 8
    assert report["samplers"]["random"]["n_seeds"] == 1 and report["episodes_evaluated"] == 8
