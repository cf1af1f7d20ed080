"""The worked examples: the installable CUSUM defence and the one-file attack, used as a
researcher would (racf list, a trial, trials, a sweep from Python), with no edit to racf."""

from __future__ import annotations

import importlib.util
import io
import json
import math
from contextlib import redirect_stdout

import pandas as pd
import pytest

from tests.conftest import EXAMPLES, run_cli
from racf.controllers import PerceptionSample

ATTACK = str(EXAMPLES / "depth_scale_attack.py")


def test_both_plugins_show_up_in_racf_list(cusum_installed, plugin_env):
    code, out = run_cli(["list", "--json", "--plugin", ATTACK])
    listed = json.loads(out)
    assert code == 0
    assert listed["estimator"]["lidar_cusum"]["origin"] == "racf-cusum"
    assert listed["attack"]["depth_scale"]["origin"].endswith("depth_scale_attack.py")
    assert listed["estimator"]["odca"]["origin"] == "racf"


@pytest.mark.slow  # two spawned workers start racf and torch: CI's slow stage runs it
def test_the_defence_and_the_attack_run_in_trials_on_spawned_workers(cusum_installed, plugin_env, tmp_path):
    code, out = run_cli(["trials", "--plugin", ATTACK, "--attack", "depth_scale", "--estimator", "lidar_cusum",
                      "--estimator-option", "h_m=0.2", "--seed", "0", "-n", "2",
                      "--workers", "2", "--json", "--out", str(tmp_path / "ts")])
    summary = json.loads(out)
    assert code == 0 and summary["n"] == 2  # the workers found both: the package by entry point, the file by RACF_PLUGINS
    rows = pd.read_parquet(tmp_path / "ts" / "results.parquet")
    assert set(rows["setting"]) == {"clean+depth_scale+lidar_cusum"} and set(rows["estimator"]) == {"lidar_cusum"}


@pytest.mark.slow  # 2.2 s, a sweep: the default run keeps under two minutes on 2 cores
def test_a_sweep_from_flags_runs_both_and_an_edited_plugin_reruns(cusum_installed, plugin_env, tmp_path):
    argv = ["sweep", "--plugin", ATTACK, "--attack", "depth_scale", "--estimator", "lidar_cusum", "--sign", "1",
            "--workers", "1", "--json", "--out", str(tmp_path / "sweep")]
    first = json.loads(run_cli(argv)[1])
    assert first["done"] == 1 and set(first["scr"]) == {"clean+depth_scale+lidar_cusum"}
    assert json.loads(run_cli(argv)[1])["reused"] == 1
    source = cusum_installed / "__init__.py"
    source.write_text(source.read_text() + "\n# edited\n")
    assert json.loads(run_cli(argv)[1])["done"] == 1  # a new id: the old result is not reused


@pytest.mark.slow
def test_a_sweep_from_python_reruns_only_what_an_edited_defence_touches(cusum_installed, plugin_env, tmp_path):
    spec = importlib.util.spec_from_file_location("sweep_from_python", EXAMPLES / "sweep_from_python.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    args = ["--signs", "1", "--workers", "1", "--out", str(tmp_path / "sweep")]
    with redirect_stdout(io.StringIO()) as out:
        assert script.main(args) == 0
    scr = json.loads(out.getvalue().split("\n}")[0] + "}")
    assert set(scr) == {"clean", "clean+odca", "clean+lidar_cusum", "clean+depth_scale", "clean+depth_scale+odca",
                        "clean+depth_scale+lidar_cusum"}
    source = cusum_installed / "__init__.py"
    source.write_text(source.read_text().replace("recover_steps: int = 10", "recover_steps: int = 12"))
    with redirect_stdout(io.StringIO()) as out:
        assert script.main(args) == 0
    assert "6 episodes (2 run, 4 reused)" in out.getvalue()


def _sample(depth: float, lidar: float) -> PerceptionSample:
    return PerceptionSample(None, depth, 0.9, lidar, 0.0)


def test_cusum_passes_agreeing_depth_and_replaces_a_biased_one_with_the_lidar(cusum_installed):
    from racf_cusum import CusumDefence

    defence = CusumDefence(k_m=0.05, h_m=0.25)
    for k in range(20):
        d = 3.0 - 0.03 * k
        assert defence.estimate(_sample(d, d + 0.01), 1.5, 0.02) == d
    assert defence.diagnostics()["flag"] == 0.0
    assert not defence.would_pass(depth=3.0, speed_mps=1.5, dt=0.02)  # 0.6 m off the LiDAR at once
    outs = [defence.estimate(_sample(2.4 - 0.03 * k + 0.6, 2.4 - 0.03 * k), 1.5, 0.02) for k in range(5)]
    assert defence.diagnostics()["flag"] == 1.0
    assert outs[-1] == pytest.approx(2.4 - 0.03 * 4)
    carried = defence.estimate(_sample(3.0, math.nan), 1.5, 0.02)  # no LiDAR: the last, moved on by odometry
    assert carried == pytest.approx(outs[-1] - 1.5 * 0.02)


def test_the_offline_benchmark_scores_an_installed_defence_step_by_step(cusum_installed):
    from racf.experiments.offline.benchmark import _estimates
    from racf.experiments.offline.methods import split_arrays, table_order
    from racf.odca import LastValuePrior, ODCA

    import numpy as np

    n = 200
    d = np.linspace(3.0, 0.6, n)
    biased = d.copy()
    biased[80:140] += 0.8
    frame = pd.DataFrame({"series_id": "s0", "t": np.arange(n) * 0.02, "d_meas": biased, "c_meas": 0.9,
                          "lidar": d, "speed": 1.5, "label": 0, "d_clean": d, "c_clean": 0.9, "d_true": d})
    model = ODCA.load(prior=LastValuePrior())
    a = split_arrays(frame, model.config.alignment)
    estimates, _ = _estimates(frame, a, model, {})
    assert table_order(estimates) == ["raw", "lidar", "ekf", "chi2", "cusum", "odca", "lidar_cusum"]
    assert np.abs(estimates["lidar_cusum"][100:140] - d[100:140]).max() < 0.05  # the LiDAR, not the biased depth


@pytest.mark.slow
def test_racf_bench_quick_scores_the_installed_defence(cusum_installed, tmp_path):
    from tests.conftest import write_bench_dataset

    data = write_bench_dataset(tmp_path / "data")
    code, out = run_cli(["bench", "--quick", "--dataset", str(data), "--out", str(tmp_path / "bench"), "--json"])
    assert code == 0
    results = json.loads(out)
    assert results["by_series"]["strong"]["lidar_cusum"]["rmse"] is not None
