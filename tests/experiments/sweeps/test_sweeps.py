"""Sweeps: bad specs refused before any work, a SIGKILLed sweep resumes to exactly the rows of
an uninterrupted one, Ray gives the local pool's rows, and the report redraws from the store."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from racf.experiments.cli import main
from racf.experiments.sweeps.run import run_sweep
from racf.experiments.sweeps.spec import SweepSpec, load_spec
from racf.experiments.sweeps.store import ResultStore

ROOT = Path(__file__).resolve().parents[3]
TINY = """name = "tiny"
mode = "grid"
repeats = 2
seed = 3

[space]
attack = ["patch_occlusion", "none"]
estimator = ["raw"]
rho = [1.0]
t_atk = [2.0]
speed = [1.5]
sign = [1]
"""


def _spec_file(tmp_path, text=TINY, name="tiny.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep")
    path = _spec_file(folder)
    summary = run_sweep(load_spec(path), TINY, folder / "a", workers=1, progress=False)  # spawning costs more than 4 episodes
    return folder, summary, ResultStore(folder / "a").rows()


def test_sweep_runs_every_episode_and_reports(uninterrupted):
    folder, summary, rows = uninterrupted
    assert summary["n"] == summary["done"] == len(rows) == 4 and summary["reused"] == 0
    assert set(summary["scr"]) == {"attack", "clean"}
    for name in ("summary.md", "summary.json", "scr_vs_rho.png", "scr_vs_t_atk.png"):
        assert (folder / "a" / name).stat().st_size > 0
    again = run_sweep(load_spec(folder / "tiny.toml"), TINY, folder / "a", workers=2, progress=False)
    assert again["done"] == 0 and again["reused"] == 4


@pytest.mark.slow
def test_sigkilled_sweep_resumes_to_the_same_rows(uninterrupted, tmp_path):
    folder, _, reference = uninterrupted
    out = tmp_path / "b"
    cmd = [sys.executable, "-m", "racf.experiments.cli", "sweep", str(folder / "tiny.toml"), "--out", str(out),
           "--workers", "1", "--json"]
    proc = subprocess.Popen(cmd, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.time() + 240
    while time.time() < deadline and len(list((out / "parts").glob("*.parquet"))) < 1:
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = len(list((out / "parts").glob("*.parquet")))
    assert 1 <= finished < 4, "the kill should land mid-sweep"
    summary = run_sweep(load_spec(folder / "tiny.toml"), TINY, out, workers=2, progress=False)
    assert summary["reused"] == finished and summary["done"] == 4 - finished
    assert not list((out / "parts").glob("*.tmp"))
    pd.testing.assert_frame_equal(ResultStore(out).rows(), reference)


@pytest.mark.slow
def test_ray_backend_gives_the_local_pool_rows(uninterrupted, tmp_path):
    folder, _, reference = uninterrupted
    run_sweep(load_spec(folder / "tiny.toml"), TINY, tmp_path / "ray", backend="ray", workers=2, progress=False)
    pd.testing.assert_frame_equal(ResultStore(tmp_path / "ray").rows(), reference)


def test_report_redraws_from_the_store_without_running(uninterrupted, capsys, tmp_path):
    folder, _, rows = uninterrupted
    (folder / "a" / "summary.md").unlink()
    assert main(["sweep", "--report", str(folder / "a")]) == 0
    assert "| attack | 2 |" in (folder / "a" / "summary.md").read_text()
    assert main(["sweep", "--report", str(folder)]) == 2
    # A result older code left in the folder (another id) is not mixed into the redrawn report.
    import shutil

    copy = tmp_path / "a"
    shutil.copytree(folder / "a", copy)
    stale = rows.iloc[[0]].assign(trial_id="attack_sign1_v1.50_seed0_000000000000", success=False)
    stale.to_parquet(copy / "parts" / "attack_sign1_v1.50_seed0_000000000000.parquet")
    assert main(["sweep", "--report", str(copy)]) == 0
    assert "| attack | 2 |" in (copy / "summary.md").read_text()
    # Results this code never made: the report says to run the sweep, and draws nothing.
    (copy / "parts" / f"{rows['trial_id'].iloc[0]}.parquet").unlink()
    capsys.readouterr()
    assert main(["sweep", "--report", str(copy)]) == 2
    assert "were not run by this code" in capsys.readouterr().err


@pytest.mark.parametrize("text, message", [
    (TINY.replace("speed = [1.5]", "speed = [1.5]\nwind = [1]"), "unknown parameter"),
    (TINY.replace('estimator = ["raw"]', "estimator = []"), "non-empty list"),
    (TINY.replace("rho = [1.0]", "rho = [1.5]"), r"rho must lie in \[0.0, 1.0\]"),
    (TINY.replace('"patch_occlusion", "none"', '"laser"'), "unknown attack"),
    (TINY.replace('["raw"]', '["kalman"]'), "estimator"),
    (TINY.replace('mode = "grid"', 'mode = "random"'), "n \\(the number of random draws\\)"),
    ("budget = 3\n" + TINY, "unknown field"),
    ("supervisor = true\n" + TINY, "supervisor must be a non-empty list of true/false"),
    ("supervisor = [1]\n" + TINY, "supervisor must be a non-empty list of true/false"),
    ('sensor_profile = "real"\n' + TINY, r"sensor_profile must be one of \('qcar2', 'ideal'\)"),
    ('sign_geometry = "post"\n' + TINY, r"sign_geometry must be one of \('plate', 'pole'\)"),
    (TINY + "\n[traffic]\ncars = [0, 9]\n", r"scenario 'cross_traffic' parameter 'cars' must be an int in \[1, 4\] cars, got 9"),
    (TINY + "\n[traffic]\nlanes = 2\n", r"unknown field\(s\) \['lanes'\] in \[traffic\]"),
    (TINY + "\n[traffic]\ncars = [1]\ngap_s = 9\n", r"parameter 'gap_s' must be a float in \[-5.0, 5.0\]"),
    (TINY + "\n[lanes]\ncars = [1]\n", r"unknown field\(s\) \['lanes'\]; allowed: .*'traffic'"),
    ("target = \"obstacle\"\n" + TINY + "\n[traffic]\ncars = [1]\n", r"\[traffic\] lists the parameters of scenario 'cross_traffic' \(a sign approach\); target 'obstacle' cannot"),
])
def test_bad_specs_are_refused_before_any_work(tmp_path, capsys, text, message):
    path = _spec_file(tmp_path, text, "bad.toml")
    with pytest.raises(ValueError, match=message):
        load_spec(path)
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "bad.toml" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_flags_make_the_same_sweep_as_the_spec(uninterrupted, tmp_path, capsys):
    _, summary, rows = uninterrupted
    flags = ["--repeats", "2", "--seed", "3", "--attack", "patch_occlusion", "none", "--estimator", "raw", "--rho", "1",
             "--t-atk", "2", "--speed", "1.5", "--sign", "1"]
    assert main(["sweep", *flags, "--out", str(tmp_path / "flags"), "--workers", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["scr"] == summary["scr"]
    flag_rows = ResultStore(tmp_path / "flags").rows()
    key = ["trial_id", "success", "failure", "stop_distance_m"]
    pd.testing.assert_frame_equal(flag_rows[key].sort_values("trial_id").reset_index(drop=True),
                                  rows[key].sort_values("trial_id").reset_index(drop=True))
    # The results folder keeps the sweep as TOML.
    assert load_spec(next((tmp_path / "flags").glob("spec.toml"))).episodes() == load_spec(
        _spec_file(tmp_path, TINY)).episodes()


def test_bad_flags_are_refused_before_any_work(tmp_path, capsys):
    assert main(["sweep", "--attack", "patch_occlusion", "--rho", "1.5", "--out", str(tmp_path / "out")]) == 2
    assert "rho must lie in [0.0, 1.0]" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
    assert main(["sweep", "smoke.toml", "--mode", "random", "--out", str(tmp_path / "out")]) == 2
    assert "n (the number of random draws)" in capsys.readouterr().err


def test_flags_replace_a_specs_fields_under_a_new_name():
    from racf.experiments.sweeps.spec import parse_spec, spec_text

    spec = parse_spec(spec_text("smoke.toml", {}, {"estimator": ["ekf"]}))
    assert spec.name.startswith("smoke-") and spec.space["estimator"] == ["ekf"]
    assert len(spec.episodes()) == 4
    assert parse_spec(spec_text("smoke.toml", {"name": "mine", "seed": 5})).name == "mine"


def test_shipped_specs_load_and_the_big_one_has_1000_paired_episodes():
    assert len(load_spec("smoke.toml").episodes()) == 8
    big = load_spec("strong-1000.toml").episodes()
    assert len(big) == len({e.trial_id for e in big}) == 1000
    # Estimators meet the same episode: four settings per seed.
    assert pd.Series([e.seed for e in big]).value_counts().eq(4).all()
    assert len(load_spec("attack-types.toml").episodes()) == 144
    with pytest.raises(ValueError, match="mode"):
        SweepSpec(name="x", mode="sobol")


def test_the_cross_traffic_spec_pairs_each_episode_with_and_without_another_car():
    episodes = load_spec("cross-traffic.toml").episodes()
    assert len(episodes) == len({e.trial_id for e in episodes}) == 512
    by_key = pd.DataFrame([{"seed": e.seed, "setting": e.setting, "cars": e.scenario_params.get("cars", 0)} for e in episodes])
    # Every seed and setting runs once on the empty map and once with one other car.
    assert by_key.groupby(["seed", "setting"])["cars"].apply(lambda cars: sorted(cars) == [0, 1]).all()
    assert (by_key.groupby("setting").size() == 64).all()


def test_a_folder_of_another_sweep_is_refused(uninterrupted):
    folder, _, _ = uninterrupted
    other = load_spec(folder / "tiny.toml")
    other = SweepSpec(name="other", mode=other.mode, repeats=1, seed=9, space=other.space)
    with pytest.raises(ValueError, match="another sweep"):
        run_sweep(other, "x", folder / "a", progress=False)


def test_an_estimators_table_gives_its_estimator_options_and_enters_the_hash():
    from racf.assets import asset_path
    from racf.experiments.sweeps.spec import parse_spec

    head = str(asset_path("checkpoints", "odca-head"))
    plain = parse_spec(TINY.replace('estimator = ["raw"]', 'estimator = ["raw", "odca"]'))
    text = plain_text = TINY.replace('estimator = ["raw"]', 'estimator = ["raw", "odca"]')
    text += f'\n[estimators.odca]\ncheckpoint = "{head}"\n'
    spec = parse_spec(text)
    assert spec.spec_hash != plain.spec_hash
    options = {e.estimator: e.estimator_options for e in spec.episodes()}
    assert options == {"raw": {}, "odca": {"checkpoint": head}}
    with pytest.raises(ValueError, match="estimators.ekf: 'ekf' is not in space.estimator"):
        parse_spec(plain_text + '\n[estimators.ekf]\nx = 1\n')
