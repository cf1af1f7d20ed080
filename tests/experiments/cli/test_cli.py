import subprocess
import sys
from pathlib import Path

import pytest

from racf.experiments.cli import main

ROOT = Path(__file__).resolve().parents[3]


def test_help_lists_the_commands(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for command in ("snapshot", "bench", "demo", "trial", "trials", "odca", "detector"):
        assert f"\n    {command} " in out


def test_bad_sign_is_a_clear_error(capsys):
    assert main(["snapshot", "--sign", "9"]) == 2
    assert "sign must be 0, 1, 2 or 3" in capsys.readouterr().err


@pytest.mark.parametrize("command", [["trial"], ["trials", "--table"], ["sweep", "smoke.toml"], ["collect"],
                                     ["attack-study"], ["demo"]])
@pytest.mark.parametrize(("flag", "choices"), [("--sensor-profile", "'qcar2', 'ideal'"),
                                               ("--sign-geometry", "'plate', 'pole'")])
def test_bad_sensor_profile_or_sign_fails_before_any_work_naming_the_choices(command, flag, choices, capsys, tmp_path):
    assert main(command + [flag, "real", "--out", str(tmp_path / "out")]) == 2
    assert f"{flag}: invalid choice: 'real' (choose from {choices})" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_snapshot_writes_the_four_pictures(tmp_path):
    assert main(["snapshot", "--sign", "3", "--width", "160", "--height", "120", "--out", str(tmp_path)]) == 0
    names = {p.name for p in tmp_path.glob("*.png")}
    assert names == {"map_top.png", "camera_rgb.png", "camera_depth.png", "lidar.png"}
    assert all(p.stat().st_size > 5000 for p in tmp_path.glob("*.png"))


@pytest.mark.slow  # nine seconds of three episodes; CI's slow stage runs it
def test_demo_tells_the_story_and_writes_three_recordings(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for setting in ("clean", "attack", "attack+odca"):
        assert setting in out
    assert "stopped in the band" in out and "failed: confirmed_lost" in out  # clean / attack+odca stop; attack does not
    assert sorted(p.name for p in tmp_path.glob("*.rrd")) == ["attack.rrd", "attack_odca.rrd", "clean.rrd"]
    assert (tmp_path / "demo_traces.png").stat().st_size > 20000
    assert (tmp_path / "moment.png").stat().st_size > 20000 and "the moment the attack acts" in out


def test_view_rejects_what_is_not_a_recording(tmp_path, capsys):
    assert main(["view", str(tmp_path / "missing.rrd")]) == 2
    assert ".rrd" in capsys.readouterr().err


@pytest.mark.slow  # 4-5 s: the default run keeps under two minutes on 2 cores
def test_odca_commands_are_listed_and_latency_prints_json(capsys):
    out = subprocess.run([sys.executable, "-m", "racf.experiments.cli", "odca", "--help"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    for command in ("pretrain-prior", "train", "evaluate"):
        assert f"\n    {command}" in out
    assert main(["bench", "odca-latency", "--steps", "120", "--json"]) == 0
    import json

    r = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert {"median_ms", "p99_ms"} <= set(r) and 0 < r["median_ms"] <= r["p99_ms"]


def test_train_without_a_dataset_is_a_clear_error(tmp_path, capsys):
    assert main(["train", "--dataset", str(tmp_path / "none")]) == 2
    assert "racf collect" in capsys.readouterr().err


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_a_reader_that_stops_reading_is_no_error():
    """`racf bag info BAG | head` once ended with "racf bag info: Broken pipe": a closed pipe ends the
    command quietly, whichever command it is (the reader here closes it before racf writes)."""
    done = subprocess.run(["bash", "-o", "pipefail", "-c", f"'{sys.executable}' -m racf.experiments.cli list --json | true"],
                          capture_output=True, text=True, timeout=120)
    assert (done.returncode, done.stderr) == (0, "")
