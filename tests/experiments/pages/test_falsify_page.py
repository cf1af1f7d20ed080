"""The falsification page: written from stored searches only; the suite's reseeding, when stored."""

from racf.experiments.pages import results_store
from racf.experiments.pages.falsify_page import RESEED_RESULT, falsification_markdown, guided_verdict


def test_an_empty_folder_says_how_to_make_each_result(tmp_path):
    page = falsification_markdown(tmp_path)
    assert "Not stored yet (`falsify-odca-dropout`)" in page and "parameters' failure" not in page


def test_the_reseeded_suite_shows_how_often_each_cases_parameters_fail_again(tmp_path, monkeypatch):
    monkeypatch.setattr(results_store, "commit", lambda root=None: "abc1234")
    replays = [{"case": "odca-sign1-confirmed_lost-x", "defence": "odca", "robustness_then_m": -1.128,
                "reseeded": {"n": 20, "violations": 0, "robustness_median_m": 0.293, "robustness_min_m": 0.157}},
               {"case": "raw-sign0-confirmed_lost-y", "defence": "raw", "robustness_then_m": -1.114,
                "reseeded": {"n": 20, "violations": 20, "robustness_median_m": -1.1, "robustness_min_m": -1.2}}]
    results_store.store_result(RESEED_RESULT, {"replays": replays}, command="racf replay-case --suite --reseed 20 --json",
                               data_dir=tmp_path)
    page = falsification_markdown(tmp_path)
    assert "| `odca-sign1-confirmed_lost-x` | odca | -1.128 | 0/20 [0.00, 0.16] | +0.293 | +0.157 |" in page
    assert "| `raw-sign0-confirmed_lost-y` | raw | -1.114 | 20/20 [0.84, 1.00] |" in page
    assert "`racf replay-case --suite --reseed 20 --json`" in page and "`abc1234`" in page
    assert "- odca: its cases' parameters fail again in 0 of 20 other draws (0.00 [0.00, 0.16])." in page


def test_guided_search_wins_only_outside_the_intervals():
    def row(falsified, median, ci):
        return {"falsified": falsified, "n_seeds": 10, "episodes_to_first_median": median, "falsification_rate_ci": ci}

    close = {"tpe": row(4, None, [0.17, 0.69]), "random": row(3, None, [0.11, 0.60])}
    assert "not a clear win" in guided_verdict(close)
    faster = {"tpe": row(10, 2.0, [0.72, 1.0]), "random": row(10, 8.0, [0.72, 1.0])}
    assert "TPE beats random search" in guided_verdict(faster)


def test_where_random_search_found_violations_is_a_table():
    from racf.experiments.pages.falsify_page import _regions

    report = {"violations_by_value": {"sign": {"0": {"n": 10, "violations": 3, "share": 0.3, "share_ci": [0.1, 0.6]},
                                               "1": {"n": 0, "violations": 0, "share": None, "share_ci": [0.0, 1.0]}}}}
    lines = _regions(report)
    assert "Random search's 10 draws broke the rule 3 times (30.0 %)" in lines[0]
    assert "| sign | 0 | 3 / 10 | 0.300 [0.100, 0.600] |" in lines and "| sign | 1 | 0 / 0 | - |" in lines
    assert _regions({}) == []
