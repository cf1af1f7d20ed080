"""The supervisor's page: each attack with the defence alone and supervised, what issue 69 asked of
it (met or not, from the numbers), and the falsification of its guarantee."""

import json

from racf.experiments.pages.supervisor_page import checks, supervisor_markdown

META = {"command": "racf sweep following-supervisor.toml", "commit": "abc", "racf": "0.1.0", "machine": "m",
        "measured": "2026-11-28"}


def _share(k, n):
    return {"k": k, "n": n, "rate": k / n, "ci": [max(k / n - 0.1, 0.0), min(k / n + 0.1, 1.0)]}


def _row(attack, estimator, free, needless, gap=1.0, finish=9.0):
    return {"attack": attack, "estimator": estimator, "n": 60, "collision_free": _share(free, 60),
            "needless_hard_brake": _share(needless, 60),
            "mean_time_gap_s_median": {"median": gap, "ci": [gap - 0.1, gap + 0.1], "n": 60},
            "finish_s_median": {"median": finish, "ci": [finish - 1, finish + 1], "n": 60}}


def _rows():
    rows = [_row("clean", "odca", 60, 7), _row("clean", "odca + supervisor", 60, 2, gap=1.05, finish=10.5),
            _row("clean+lead_hide", "odca", 11, 0), _row("clean+lead_hide", "odca + supervisor", 58, 0),
            _row("clean+lead_phantom", "odca", 51, 35), _row("clean+lead_phantom", "odca + supervisor", 60, 1),
            _row("clean+lead_frustum[adaptive]", "odca", 6, 0), _row("clean+lead_frustum[adaptive]",
                                                                     "odca + supervisor", 10, 0)]
    return {f"{r['attack']}|{r['estimator']}": r for r in rows}


def test_what_was_asked_is_judged_from_the_numbers():
    lines = checks(_rows())
    text = "\n".join(lines)
    assert "the lead hidden from camera and LiDAR: collision-free 0.97" in text and "(N 60; asked >= 0.95): met" in text
    # The adaptive spoof lies outside the assumptions: nothing is asked of it.
    assert "adaptive" not in text
    assert "needless hard brakes in 0.03" in text and "needless hard brakes in 0.02" in text
    assert "mean time gap: 1.05 s under the supervisor, 1.00 s alone (medians), +5% (asked within 25 %): met" in text
    # 10.5 / 9.0 = +17 %: within 25 %; at 12.0 / 9.0 = +33 % it would not be.
    assert "time to finish: 10.50 s under the supervisor, 9.00 s alone (medians), +17% (asked within 25 %): met" in text
    slow = _rows()
    slow["clean|odca + supervisor"] = {**slow["clean|odca + supervisor"],
                                       "finish_s_median": {"median": 12.0, "ci": [11.0, 13.0]}}
    assert "+33% (asked within 25 %): **not met**" in "\n".join(checks(slow))


def test_the_page_pairs_each_defence_with_itself_supervised_and_says_what_is_missing(tmp_path):
    assert "Not stored yet (`following-supervisor`)" in supervisor_markdown(tmp_path)
    assert "Not stored yet (`falsify-guarantee`)" in supervisor_markdown(tmp_path)
    (tmp_path / "following-supervisor.json").write_text(json.dumps({"meta": META, "rows": _rows()}))
    page = supervisor_markdown(tmp_path)
    assert "| the lead hidden from camera and LiDAR | yes | odca | 60 | 0.18 [" in page
    assert "| the lead hidden from camera and LiDAR | yes | odca + supervisor | 60 | 0.97 [" in page
    assert page.index("| none |") < page.index("the lead hidden") < page.index("a phantom car")
    report = {"meta": META, "episodes_evaluated": 400,
              "samplers": {"random": {"n_seeds": 5, "falsified": 0, "lowest_robustness_m": 0.08},
                           "tpe": {"n_seeds": 5, "falsified": 0, "lowest_robustness_m": 0.05}}}
    (tmp_path / "falsify-guarantee.json").write_text(json.dumps(report))
    page = supervisor_markdown(tmp_path)
    assert "400 episodes in 10 searches (random, tpe): 0 of the searches found a violation; the lowest robustness " \
           "any episode left: +0.050 m. The random sampler alone (the parameter space drawn uniformly): 5 searches, " \
           "0 violated, lowest +0.080 m." in page
    # Inside the assumptions all told: 400 episodes, short of the 1,000 asked; with the sign's 700 more, met.
    assert "Inside the assumptions, all told: 400 episodes at one commit (abc), 0 searches with a violation (a " \
           "contact, or the stop rule broken: the line run, or no rest within 3 s of the braking window) (asked: at " \
           "least 1,000 episodes at one commit, none): **not met**." in page
    (tmp_path / "falsify-guarantee-sign.json").write_text(json.dumps({**report, "episodes_evaluated": 700}))
    assert "all told: 1100 episodes at one commit (abc), 0 searches" in supervisor_markdown(tmp_path) and \
           "none): met." in supervisor_markdown(tmp_path)
    # The sign's searched at another commit (measured_on names it): two commits, not met.
    other = {**report, "episodes_evaluated": 700, "meta": {**META, "measured_on": "def"}}
    (tmp_path / "falsify-guarantee-sign.json").write_text(json.dumps(other))
    assert "all told: 1100 episodes at 2 commits (abc, def), 0 searches" in supervisor_markdown(tmp_path) and \
           "none): **not met**." in supervisor_markdown(tmp_path)
    (tmp_path / "falsify-guarantee-sign.json").write_text(json.dumps({**report, "episodes_evaluated": 700}))
    found = {**report, "samplers": {**report["samplers"], "tpe": {**report["samplers"]["tpe"], "falsified": 1}}}
    (tmp_path / "falsify-guarantee.json").write_text(json.dumps(found))
    assert "1 searches with a violation" in supervisor_markdown(tmp_path)



def test_the_served_lies_are_a_table_and_a_verdict_from_the_numbers(tmp_path):
    assert "Not stored yet (`served-lies`)" in supervisor_markdown(tmp_path)
    rows = [{"lie": "always 4 m", "supervisor": False, "n": 20, "stopped": 20, "scr": 1.0, "scr_ci": [0.84, 1.0],
             "lies": 3368, "outvoted_steps": 2553, "invalid": 0, "fallback_steps": 0},
            {"lie": "always 4 m", "supervisor": True, "n": 20, "stopped": 19, "scr": 0.95, "scr_ci": [0.76, 0.99],
             "lies": 3400, "outvoted_steps": 2600, "invalid": 0, "fallback_steps": 0}]
    (tmp_path / "served-lies.json").write_text(json.dumps({"meta": META, "rows": rows}))
    page = supervisor_markdown(tmp_path)
    assert "| always 4 m | no | 20 | 20 (1.00 [0.84, 1.00]) | 3368 | 2553 | 0 | 0 |" in page
    assert "39 of 40 episodes (asked: all): **not met**." in page
    rows[1] = {**rows[1], "stopped": 20}
    (tmp_path / "served-lies.json").write_text(json.dumps({"meta": META, "rows": rows}))
    assert "40 of 40 episodes (asked: all): met." in supervisor_markdown(tmp_path)


def test_the_plain_link_spoof_is_met_only_where_every_supervised_row_stops_in_95_percent(tmp_path):
    lies = [{"lie": "always 4 m", "supervisor": True, "n": 20, "stopped": 20, "scr": 1.0, "scr_ci": [0.84, 1.0],
             "lies": 3368, "outvoted_steps": 2553, "invalid": 0, "fallback_steps": 0}]
    spoof = [{"lie": "link_spoof (5 m, plain link)", "supervisor": False, "n": 60, "stopped": 31, "scr": 31 / 60,
              "scr_ci": [0.39, 0.64], "lies": None, "outvoted_steps": 0, "invalid": 0, "fallback_steps": 0},
             {"lie": "link_spoof (5 m, plain link)", "supervisor": True, "n": 60, "stopped": 56, "scr": 56 / 60,
              "scr_ci": [0.84, 0.97], "lies": None, "outvoted_steps": 12, "invalid": 0, "fallback_steps": 0}]
    (tmp_path / "served-lies.json").write_text(json.dumps({"meta": META, "rows": lies}))
    assert "Not measured in the stored file." in supervisor_markdown(tmp_path)
    (tmp_path / "served-lies.json").write_text(json.dumps({"meta": META, "rows": lies, "link_spoof": spoof}))
    page = supervisor_markdown(tmp_path)
    assert "| no | 60 | 31 (0.52 [0.39, 0.64]) | 0 | 0 | 0 |" in page
    # 56 of 60 is 0.933: under 0.95.
    assert "Supervised, the car stops in 56 of 60 (asked: at least 0.95): **not met**." in page
    spoof[1] = {**spoof[1], "stopped": 57, "scr": 57 / 60}
    (tmp_path / "served-lies.json").write_text(json.dumps({"meta": META, "rows": lies, "link_spoof": spoof}))
    assert "57 of 60 (asked: at least 0.95): met." in supervisor_markdown(tmp_path)


def test_the_rows_over_raw_depth_and_the_ekf_say_what_to_run_until_stored(tmp_path):
    page = supervisor_markdown(tmp_path)
    assert "## Over raw depth and the EKF" in page and "Not stored yet (`following-supervisor-others`)" in page


def test_a6_is_a_table_per_sign_and_a_verdict_against_the_budget(tmp_path):
    assert "Not stored yet (`route-error`)" in supervisor_markdown(tmp_path)
    rows = [{"sign": 0, "speed": 1.0, "seed": 1000, "steps": 100, "ahead_max_m": 0.02, "behind_max_m": 0.03,
             "success": True, "stop_distance_m": 0.2},
            {"sign": 0, "speed": 1.5, "seed": 1001, "steps": 100, "ahead_max_m": 0.05, "behind_max_m": 0.01,
             "success": False, "stop_distance_m": 0.9},
            {"sign": 1, "speed": 1.0, "seed": 1000, "steps": 100, "ahead_max_m": 0.0, "behind_max_m": 0.09,
             "success": True, "stop_distance_m": 0.3}]
    summary = {"episodes": 3, "behind_max_m": 0.09, "ahead_max_m": 0.05, "stopped_in_band": 2}
    (tmp_path / "route-error.json").write_text(json.dumps({"meta": META, "summary": summary, "rows": rows}))
    page = supervisor_markdown(tmp_path)
    # Sign 0: the larger of each column over its two episodes, one of two stopped.
    assert "| 0 | 2 | 0.030 | 0.050 | 1 of 2 |" in page and "| 1 | 1 | 0.090 | 0.000 | 1 of 1 |" in page
    assert "At most 0.090 m behind over 3 episodes, against the budget of 0.1 m: within it." in page
    summary["behind_max_m"] = 0.11
    (tmp_path / "route-error.json").write_text(json.dumps({"meta": META, "summary": summary, "rows": rows}))
    assert "against the budget of 0.1 m: **past it**." in supervisor_markdown(tmp_path)
