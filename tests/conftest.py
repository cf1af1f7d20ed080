"""Fixtures shared across the test packages: the example plug-ins, installed or loaded."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import settings

from racf.experiments.data.dataset import COLUMNS, make_splits
from racf.odca.synthetic import approach_curve
from racf.plugins import REGISTRIES

# CI draws the same examples on every run (a failing CI blocks a landing, so nothing in it may
# fail by chance); elsewhere hypothesis explores, and its database keeps what it found.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
# make mutate: the same examples for every mutant, and none remembered from another mutant's run (a
# failure kept in the database would be replayed against every mutant after it).
settings.register_profile("mutation", derandomize=True, deadline=None, database=None)
# Elsewhere too, no deadline: a test's first example pays for imports, and a loaded machine stretches
# it past any deadline (a deadline is a timing test of the machine, not of racf).
settings.register_profile("local", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "local")

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def run_cli(argv: list[str]) -> tuple[int, str]:
    """``racf ARGV`` in this process: its exit code and what it printed on stdout."""
    import io
    from contextlib import redirect_stdout

    from racf.experiments.cli import main

    out = io.StringIO()
    with redirect_stdout(out):
        code = main(argv)
    return code, out.getvalue()


def _forget_plugins() -> None:
    """The registries read the entry points afresh on next use."""
    for registry in REGISTRIES.values():
        registry._plugins = None


@pytest.fixture(scope="session")
def cusum_wheel_site(tmp_path_factory) -> Path:
    """The example defence installed once by pip from its own ``pyproject.toml`` (its entry point
    included) into a folder of its own: what ``pip install examples/racf-cusum`` puts in site-packages."""
    return _pip_install_example(tmp_path_factory, "racf-cusum")


def install_cusum(site: Path, installed: Path) -> Path:
    """A copy of the pip-installed example in ``site``, a folder to put on the path (a test may edit
    it); importlib.metadata finds it as it finds any installed distribution. Returns the package's folder."""
    shutil.copytree(installed, site)
    return site / "racf_cusum"


@pytest.fixture
def cusum_installed(tmp_path, monkeypatch, cusum_wheel_site):
    """The example defence installed for one test (and the worker processes it spawns)."""
    site = tmp_path / "site"
    package = install_cusum(site, cusum_wheel_site)
    for name in [m for m in sys.modules if m.split(".")[0] == "racf_cusum"]:  # another test's copy
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.setenv("PYTHONPATH", str(site))
    _forget_plugins()
    yield package
    _forget_plugins()


def _pip_install_example(tmp_path_factory, folder: str) -> Path:
    """An example package installed by pip from its own ``pyproject.toml`` (its entry points included)
    into a folder of its own: what ``pip install examples/FOLDER`` puts in site-packages."""
    site = tmp_path_factory.mktemp(folder)
    # Built from a copy: test processes running side by side never share the build's scratch folders.
    source = shutil.copytree(EXAMPLES / folder, tmp_path_factory.mktemp(f"{folder}-src") / folder,
                             ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
                           "--target", str(site), str(source)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    return site


def _use_example(site: Path, installed: Path, module: str, monkeypatch) -> Path:
    """A copy of an installed example on the path of this process and its workers; the package's folder."""
    shutil.copytree(installed, site)
    for name in [m for m in sys.modules if m.split(".")[0] == module]:  # another test's copy
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")])))
    _forget_plugins()
    return site / module


@pytest.fixture(scope="session")
def parked_car_site(tmp_path_factory) -> Path:
    return _pip_install_example(tmp_path_factory, "racf-parked-car")


@pytest.fixture
def parked_car_installed(tmp_path, monkeypatch, parked_car_site):
    """The example scenario installed for one test (and the worker processes it spawns); its package folder."""
    yield _use_example(tmp_path / "parked-site", parked_car_site, "racf_parked_car", monkeypatch)
    _forget_plugins()


@pytest.fixture(scope="session")
def pedestrian_site(tmp_path_factory) -> Path:
    return _pip_install_example(tmp_path_factory, "racf-pedestrian")


@pytest.fixture
def pedestrian_installed(tmp_path, monkeypatch, pedestrian_site):
    """The example pedestrian scenario installed for one test (and the worker processes it spawns)."""
    yield _use_example(tmp_path / "pedestrian-site", pedestrian_site, "racf_pedestrian", monkeypatch)
    _forget_plugins()


@pytest.fixture(scope="session")
def cut_in_site(tmp_path_factory) -> Path:
    return _pip_install_example(tmp_path_factory, "racf-cut-in")


@pytest.fixture
def cut_in_installed(tmp_path, monkeypatch, cut_in_site):
    """The example cut-in scenario installed for one test (and the worker processes it spawns)."""
    yield _use_example(tmp_path / "cut-in-site", cut_in_site, "racf_cut_in", monkeypatch)
    _forget_plugins()


@pytest.fixture(scope="session")
def time_to_line_site(tmp_path_factory) -> Path:
    return _pip_install_example(tmp_path_factory, "racf-time-to-line")


@pytest.fixture
def time_to_line_installed(tmp_path, monkeypatch, time_to_line_site):
    """The example metric installed for one test (and the worker processes it spawns); its package folder."""
    yield _use_example(tmp_path / "ttl-site", time_to_line_site, "racf_time_to_line", monkeypatch)
    _forget_plugins()


@pytest.fixture
def plugin_env(monkeypatch):
    """Plug-in files loaded by a test are forgotten after it."""
    monkeypatch.setenv("RACF_PLUGINS", "")  # restored (unset) after the test, whatever it loaded
    _forget_plugins()
    yield
    _forget_plugins()


def write_bench_dataset(folder, n_series=12, seed=0):
    """A small synthetic dataset folder in the shape ``racf collect`` writes (for ``racf bench --quick``)."""
    rng = np.random.default_rng(seed)
    frames = []
    for i in range(n_series):
        parts = []
        for slot, target in enumerate((f"sign{i % 5}", f"sign{(i + 1) % 5}")):
            d = approach_curve(rng, 220)
            lidar = d + rng.normal(0, 0.01, d.size)
            speed = np.clip(-np.gradient(pd.Series(d).ffill().bfill().to_numpy(), 0.02), 0, 3)
            parts.append(pd.DataFrame({"slot": slot, "target": target, "d_clean": d, "d_true": d + 0.005,
                                       "c_clean": np.where(np.isfinite(d), 0.9, 0.0), "lidar": lidar,
                                       "speed": speed}))
        s = pd.concat(parts, ignore_index=True)
        n = len(s)
        s = s.assign(series_id=f"drive{i}", drive_seed=i, t=np.arange(n) * 0.02, speed_set=1.0, bearing=0.0,
                     sign_in_view=np.isfinite(s["d_clean"]), detected=np.isfinite(s["d_clean"]),
                     scan_new=np.arange(n) % 5 == 0, scan_fov_mm=[np.zeros(4, np.uint16)] * n, steering=0.0,
                     yaw_rate=0.0, accel=0.0, x=0.0, y=0.0, yaw=0.0, dist_to_stop_line=s["d_clean"], brake=False,
                     x_est=0.0, y_est=0.0, yaw_est=0.0, fix_x=0.0, fix_y=0.0, fix_yaw=0.0,
                     d_size=s["d_true"] * rng.normal(1.0, 0.03, n), size_std=0.04 * s["d_true"])
        frames.append(s[list(COLUMNS)])
    data = pd.concat(frames, ignore_index=True)
    folder.mkdir(parents=True, exist_ok=True)
    data.to_parquet(folder / "dataset.parquet", index=False)
    (folder / "split.json").write_text(json.dumps({"seed": 0, "shares": [0.7, 0.1, 0.2],
                                                   **make_splits(data, seed=0)}))
    return folder


def start_service(defence, stops: list, max_requests: float = float("inf"), keys=None,
                  endpoint: str = "tcp://127.0.0.1:0", **kwargs) -> str:
    """``serve(defence, ...)`` in a daemon thread (its stop appended to ``stops``); returns its endpoint."""
    import threading

    from racf.experiments.service.server import serve

    bound, stop, ready = [], threading.Event(), threading.Event()
    offers = None if defence is None else {defence: {}}
    thread = threading.Thread(target=serve, args=(endpoint, offers),
                              kwargs={"ready": lambda e: (bound.append(e), ready.set()), "max_requests": max_requests,
                                      "stop": stop, "keys": keys, **kwargs}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not ready.wait(0.05):  # bound, or the thread is gone (its bind refused): no minute's wait for nothing
        assert thread.is_alive() and time.monotonic() < deadline, f"the service at {endpoint} did not start"
    stops.append((stop, thread))
    return bound[0]


@pytest.fixture
def service():
    """A function that starts a service (see :func:`start_service`) and returns its endpoint; every
    one is stopped after the test."""
    stops = []
    yield lambda defence, max_requests=float("inf"), **kw: start_service(defence, stops, max_requests, **kw)
    for stop, thread in stops:
        stop.set()
        thread.join(5)


def _test_fleet():
    import numpy as np

    from racf.sim.radio import FleetKeys

    return FleetKeys.draw(np.random.default_rng(0))


#: A fleet's keys for the tests that sign messages by hand (the car trusts ``TEST_FLEET.trust_store()``).
TEST_FLEET = _test_fleet()
