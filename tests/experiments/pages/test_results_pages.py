"""The results pages come from stored results only: a stored number appears, with its command and
commit; a result not stored says how to make it, and no page invents one."""

import json
import re

import pytest

from racf.experiments.pages import results_store
from racf.experiments.pages.results_pages import RESULT_PAGES, readme_table


def _settings(scr):
    return {"n": 30, "scr": scr, "scr_ci": [scr - 0.1, min(1.0, scr + 0.1)], "asr": 1 - scr,
            "asr_ci": [0.0, 0.2], "dt_brake_mean": 0.1234, "dt_brake_std": 0.01, "n_latency": 30,
            "scr_attack_before_t_star": scr, "scr_attack_before_t_star_ci": [0.5, 1.0], "n_attack_before_t_star": 16}


@pytest.fixture
def data_dir(tmp_path, monkeypatch):
    monkeypatch.setattr(results_store, "commit", lambda root=None: "abc1234")
    table = {name: _settings(scr) for name, scr in (("clean", 1.0), ("attack", 0.4567), ("attack+odca", 0.9876))}
    results_store.store_result("closed-loop-table", {"settings": table}, command="racf trials --table --json",
                               data_dir=tmp_path, sensor_profile="qcar2")
    return tmp_path


def test_a_stored_number_reaches_its_page_with_its_command_and_commit(data_dir):
    page = RESULT_PAGES["results/closed-loop.md"](data_dir)
    assert "0.46 [0.36, 0.56]" in page and "0.99 [0.89, 1.00]" in page
    assert "`racf trials --table --json`" in page and "`abc1234`" in page and "sensor profile qcar2" in page


def test_a_result_not_stored_says_how_to_make_it(data_dir):
    page = RESULT_PAGES["results/adaptive-attacks.md"](data_dir)
    assert "Not stored yet (`adaptive`)" in page and "racf sweep adaptive.toml" in page


def test_the_paper_table_quotes_the_paper_beside_the_measurement(data_dir):
    table = readme_table(data_dir)
    assert "| patch attack, no defence: SCR | 0.17 | 0.46" in table
    assert "docs/results/closed-loop.md" in table



def test_the_offline_page_shows_the_clean_pass_through_of_each_split(data_dir):
    cell = {"rmse": 0.05, "rmse_ci": [0.04, 0.06], "n": 100}
    per_preset = {p: {"odca": cell} for p in ("weak", "mid", "strong")}
    clean = {"by_series": {"unchanged_share": 0.99875, "n_depth": 2794},
             "leave_target_out": {"unchanged_share": 1.0, "n_depth": 7201}, "odca_rmse_vs_input": 0.0}
    results_store.store_result("offline-bench", {"results": {"by_series": per_preset}, "clean": clean},
                               command="racf bench --json", data_dir=data_dir, sensor_profile="qcar2")
    page = RESULT_PAGES["results/offline-benchmark.md"](data_dir)
    assert "by series 99.88 % of 2,794 steps; leave target out 100.00 % of 7,201 steps" in page

def test_a_stored_pairing_reaches_the_speed_page_with_its_baseline(data_dir):
    from racf.experiments.bench.paired import PairedResult

    paired = PairedResult("attack+odca", 6, old_ms=(6.0, 5.0, 7.0), new_ms=(5.0, 4.5, 6.3)).to_dict()
    results_store.store_result("speed-paired", {"paired": paired}, command="racf bench paired --json",
                               data_dir=data_dir, baseline="dc58729")
    page = RESULT_PAGES["results/speed.md"](data_dir)
    assert "against `dc58729`: new / old 0.900 (median of 3 rounds, 0.833-0.900)" in page
    assert "| 1 | 6.000 | 5.000 | 0.833 |" in page


def test_every_page_renders_from_an_empty_folder(tmp_path):
    for name, make in RESULT_PAGES.items():  # a title first, after the page's settings if it has any
        text = make(tmp_path)
        assert re.sub(r"\A---\n.*?\n---\n\n", "", text, flags=re.S).startswith("# "), name


def test_the_store_writes_strict_json_with_its_provenance(tmp_path, monkeypatch):
    monkeypatch.setattr(results_store, "commit", lambda root=None: "abc1234")  # whatever the checkout holds now
    path = results_store.store_result("x", {"v": 1.5}, command="racf x", data_dir=tmp_path, detector="learned")
    data = json.loads(path.read_text())
    assert data["v"] == 1.5 and data["meta"]["command"] == "racf x" and data["meta"]["detector"] == "learned"
    assert {"commit", "racf", "measured", "machine"} <= set(data["meta"])
    with pytest.raises(ValueError):
        results_store.store_result("x", {"v": float("nan")}, command="racf x", data_dir=tmp_path)


def test_the_store_reads_a_sweeps_folder(tmp_path):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    (sweep / "summary.json").write_text(json.dumps({"attack": _settings(0.5)}))
    (sweep / "stealth.json").write_text(json.dumps([{"attack": "delay"}]))
    assert results_store.load_source(sweep) == {"settings": {"attack": _settings(0.5)}, "stealth": [{"attack": "delay"}]}


def test_bad_sources_are_one_line_and_exit_2(tmp_path, capsys):
    (tmp_path / "list.json").write_text("[1, 2]")
    assert results_store.main(["x", str(tmp_path / "list.json"), "--command", "c", "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "a result is a JSON object" in err
    assert not (tmp_path / "x.json").exists()


def _counts(recall, fp_rate, n=100):
    return {"n_frames": n, "n_positive": n, "n_hit": int(recall * n), "n_fp": int(fp_rate * n), "recall": recall,
            "recall_ci": [recall - 0.05, min(1.0, recall + 0.05)], "fp_rate": fp_rate, "fp_rate_ci": [0.0, fp_rate + 0.01]}


def _detector_row(recall, fp_rate):
    held = {**_counts(recall, fp_rate), "by_kind": {"sign": _counts(recall, fp_rate)},
            "by_band": {"0.3-1 m": _counts(recall, fp_rate)}}
    return {"heldout": held, "red_squares": _counts(0.0, fp_rate), "recall": recall, "recall_ci": [0.9, 1.0],
            "n_positive": 450, "fp_rate": fp_rate, "fp_rate_ci": [0.0, 0.01], "n_frames": 2572,
            "ms_per_frame_one_core": 2.5}


def test_the_detector_page_says_whether_the_segmenter_earns_the_default(tmp_path, monkeypatch):
    monkeypatch.setattr(results_store, "commit", lambda root=None: "abc1234")
    rows = {"classical": _detector_row(0.95, 0.005), "learned": _detector_row(0.94, 0.003)}
    results_store.store_result("bench-detector", {"detectors": rows}, command="racf bench-detector --json",
                               data_dir=tmp_path)
    page = RESULT_PAGES["results/detector-and-sticker.md"](tmp_path)
    assert "does not on: held-out recall, drive recall; the classical detector stays the default" in page
    assert "| learned | 0.940 [0.890, 0.990] (100) | 0.940 [0.890, 0.990] (100) |" in page  # by kind, by band
    rows["learned"] = _detector_row(0.97, 0.001)
    results_store.store_result("bench-detector", {"detectors": rows}, command="racf bench-detector --json",
                               data_dir=tmp_path)
    assert "beats the classical detector on all four counts" in RESULT_PAGES["results/detector-and-sticker.md"](tmp_path)


def test_a_result_from_uncommitted_code_is_refused_unless_forced_and_then_marked(tmp_path, monkeypatch):
    import json

    from racf.experiments.pages.results_format import meta_lines

    monkeypatch.setattr(results_store, "commit", lambda root=None: "abc1234+changes")
    with pytest.raises(ValueError, match="differs from its commit"):
        results_store.store_result("x", {"a": 1}, command="racf trials", data_dir=tmp_path)
    assert not (tmp_path / "x.json").exists()
    assert results_store.main(["x", str(_json(tmp_path)), "--command", "racf trials", "--data-dir", str(tmp_path)]) == 2
    path = results_store.store_result("x", {"a": 1}, command="racf trials", data_dir=tmp_path, force=True)
    meta = json.loads(path.read_text())["meta"]
    assert meta["uncommitted"] is True and "uncommitted changes" in meta_lines(meta)[0]


def _json(folder):
    path = folder / "source.json"
    path.write_text('{"a": 1}')
    return path


def test_a_superseded_result_says_so_on_its_provenance_line():
    from racf.experiments.pages.results_format import meta_lines

    meta = {"command": "racf sweep x.toml", "commit": "abc1234", "racf": "0.1.0", "machine": "2 CPU cores",
            "measured": "2026-11-28"}
    assert "Superseded" not in meta_lines(meta)[0]
    line = meta_lines({**meta, "superseded": "the code changed"})[0]
    assert line.endswith("**Superseded: the code changed.**")


def test_the_service_probes_are_a_before_and_after_table():
    from racf.experiments.pages.service_page import probes_markdown

    assert "Not stored yet (`service-probes`)" in "\n".join(probes_markdown({}))
    half = {"connections": 300, "server_mb_before": 129.0, "server_mb_open": 441.2, "server_mb_after": 441.2,
            "after_s": 11.0, "closed_by_server": 0}
    spelt = {"spellings": 20, "hellos_s": 148.3, "answers": {"opened": 19, "refused": 1},
             "served_car": {"lost": 347, "steps": 400}}
    ranged = {"opened": 1024, "asked": 1024, "other_range_served": False}
    kept = {"alive_resetting": 16, "alive_pinging": 0, "sessions": 100, "after_s": 6.0, "idle_s": 2.0}
    run = {"half_sent": half, "spellings": spelt, "range": ranged, "keep_alive": kept}
    meta = {"commit": "abc", "before": "ff56873", "command": "racf bench-service-probes --json", "measured": "2026-11-29",
            "racf": "0.1.0", "machine": "2 CPU cores"}
    page = "\n".join(probes_markdown({"service-probes": {"meta": meta,
                                                         "before": run, "after": run}}))
    assert "| 300 connections half-sending a 1 MiB frame | 129 -> 441 MB open -> 441 MB 11 s later; 0 of 300 closed" in page
    assert "20 hellos in 148.30 s (19 opened, 1 refused); the served car lost 347 of 400 steps" in page
    assert "1024 of 1024 sessions opened; a car from another range served: no" in page
    assert "16 of 100 resetting and 0 of 100 pinging hold a session 6 s on (idle 2 s)" in page


def test_a_result_measured_on_an_earlier_commit_names_it_and_where_it_was_stored():
    from racf.experiments.pages.results_format import meta_lines

    meta = {"command": "racf sweep x.toml", "commit": "bbbbbbb", "racf": "0.1.0", "machine": "2 CPU cores",
            "measured": "2026-11-29"}
    assert "*on commit* `bbbbbbb` (racf" in meta_lines(meta)[0]
    assert "*on commit* `aaaaaaa` (stored at `bbbbbbb`) (racf" in meta_lines({**meta, "measured_on": "aaaaaaa"})[0]
