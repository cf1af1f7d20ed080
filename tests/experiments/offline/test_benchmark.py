"""`racf bench --quick` end to end on a small synthetic dataset folder: outputs, JSON shape,
strict JSON, same numbers on a rerun (trained models reused), clear errors."""

import json

import numpy as np
import pandas as pd
import pytest

from tests.conftest import write_bench_dataset
from racf.experiments.cli import main
from racf.experiments.offline.benchmark import BenchConfig
from racf.experiments.offline.methods import METHODS


def _bench_json(data, out, *flags: str) -> dict:
    import io
    from contextlib import redirect_stdout

    buf = io.StringIO()
    with redirect_stdout(buf):
        code = main(["bench", "--quick", "--dataset", str(data), "--out", str(out), "--json", *flags])
    assert code == 0
    return json.loads(buf.getvalue())


@pytest.fixture(scope="module")
def bench_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("bench")
    data = write_bench_dataset(root / "data")
    out = root / "out"
    return out, [_bench_json(data, out, "--no-ablation")], data  # the ablation's seven heads: in the slow test


@pytest.mark.slow  # the quick benchmark (20 s): the default suite keeps under two minutes
def test_json_has_every_split_preset_and_method(bench_runs):
    _, (results,), _ = bench_runs
    for split in ("by_series", "leave_target_out"):
        for preset in ("weak", "mid", "strong"):
            for method in METHODS:
                row = results[split][preset][method]
                for key in ("rmse", "mae", "rmse_true"):
                    assert isinstance(row[key], float) and row[key] >= 0, (split, preset, method, key)
            for method in ("chronos", "softs", "nhits", "dlinear", "nlinear"):
                assert results[split][preset][method]["rmse_h16"] is not None
            n = {results[split][preset][m]["n"] for m in METHODS}
            assert len(n) == 1  # every method is scored on the same steps
            odca = results[split][preset]["odca"]
            assert odca["n_draws"] == 2 and len(odca["rmse_draws"]) == 2
            assert odca["rmse"] == pytest.approx(np.mean(odca["rmse_draws"]))  # the mean over the draws
            low, high = odca["rmse_ci"]
            assert low <= high
    assert 0 <= results["clean"]["odca_rmse_vs_input"] < 0.5
    assert results["wall_s"] > 0
    assert results["complexity"]["odca"]["trainable"] == 917


@pytest.mark.slow  # the quick benchmark (20 s): the default suite keeps under two minutes
def test_odca_repairs_what_raw_depth_and_the_forecasters_do_not_and_passes_clean_input_through(bench_runs):
    """The benchmark's claims on this dataset (seeded, so the numbers are fixed): the corruption
    grows from the weak to the strong preset; under the mid and strong ones ODCA's error is below
    raw depth's and the frozen prior's alone; fed clean series, it leaves most depths as they
    are (Proposition 1: the gate repairs only when the witnesses disagree)."""
    _, (results,), _ = bench_runs
    for split in ("by_series", "leave_target_out"):
        raw = [results[split][preset]["raw"]["rmse"] for preset in ("weak", "mid", "strong")]
        assert raw[0] < raw[1] < raw[2], (split, raw)
        for preset in ("mid", "strong"):
            row = results[split][preset]
            assert row["odca"]["rmse"] < min(row["raw"]["rmse"], row["chronos"]["rmse"]), (split, preset)
        assert results["clean"][split]["unchanged_share"] >= 0.8, results["clean"][split]


@pytest.mark.slow  # the quick benchmark (20 s): the default suite keeps under two minutes
def test_results_folder_holds_strict_json_tables_and_figures(bench_runs):
    out, (results,), _ = bench_runs

    def reject(token):
        raise AssertionError(f"non-strict JSON constant {token}")

    stored = json.loads((out / "results.json").read_text(), parse_constant=reject)
    assert stored["by_series"]["strong"]["odca"]["rmse"] == results["by_series"]["strong"]["odca"]["rmse"]
    for name in ("recovery", "recovery_true", "recovery_moving", "sensors_strong", "bd_rgr", "complexity",
                 "horizon", "error_sources_strong"):
        assert (out / "tables" / f"{name}.md").stat().st_size > 0, name
    csv = pd.read_csv(out / "tables" / "recovery.csv")
    assert len(csv) == 2 * 3 * len(METHODS)
    pngs = sorted(p.name for p in (out / "figures").glob("*.png"))
    assert pngs == sorted(["recovery_by_series.png", "recovery_leave_target_out.png", "diagnostics_by_series.png",
                           "diagnostics_leave_target_out.png", "resilience_radar.png", "complexity.png",
                           "qualitative_strong.png"])
    assert "Recovery" in (out / "README.md").read_text()


@pytest.mark.slow
def test_rerun_reuses_trained_models_gives_the_same_numbers_and_adds_the_ablation(bench_runs):
    out, (first,), data = bench_runs
    second = _bench_json(data, out)  # with the loss ablation this time
    for split in ("by_series", "leave_target_out"):
        assert all(v["train_s"] is not None for v in first["training"][split]["nf"].values())
        assert all(v["train_s"] is None for v in second["training"][split]["nf"].values())
        assert first[split] == second[split]
    assert [r["objective"] for r in second["ablation"]] == ["L_ID", "L_ID + L_Delta0", "L_ID + L_Delta0 + L_cons",
                                                            "L_ID + L_Delta0 + L_kin", "full",
                                                            "full, two-witness gate", "full, no kinematics"]
    assert (out / "tables" / "ablation.md").stat().st_size > 0


def test_bad_input_is_rejected_before_any_work(tmp_path, capsys):
    assert main(["bench", "--dataset", str(tmp_path / "missing"), "--out", str(tmp_path / "o")]) == 2
    assert "racf collect" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    with pytest.raises(ValueError, match="presets"):
        BenchConfig(presets=("extreme",))
    with pytest.raises(ValueError, match="splits"):
        BenchConfig(splits=())
    with pytest.raises(ValueError, match="draws"):
        BenchConfig(draws=0)
    assert main(["bench", "--split", "random"]) == 2
