"""Metrics, declared once: the result row is the episode's identity and then each metric's fields in
their declared order, and a field's default summary follows its declared kind."""

import math

import pandas as pd
import pytest

from racf.experiments.episode.runner import IDENTITY
from racf.experiments.metrics import Field, Metric
from racf.plugins import METRICS
from racf.stats import median_ci, wilson_interval


class _Probe(Metric):
    name = "probe"
    fields = (Field("hit", False, "", "a flag", "rate"), Field("gap_m", math.nan, "m", "a gap", "median"),
              Field("note", None, "", "not summarised"))


def test_the_default_summary_follows_each_fields_kind():
    rows = pd.DataFrame({"hit": [True, False, True, None], "gap_m": [0.1, 0.3, float("nan"), 0.2], "note": "x"})
    s = _Probe().summarize(rows, attacked=False)
    assert s["n_hit"] == 3 and s["hit_rate"] == pytest.approx(2 / 3) and s["hit_rate_ci"] == list(wilson_interval(2, 3))
    assert s["n_gap_m"] == 3 and (s["gap_m_median"], s["gap_m_ci"]) == median_ci([0.1, 0.3, 0.2])
    assert not [k for k in s if "note" in k]


def test_racfs_own_metrics_declare_the_result_rows_columns_once():
    names = sorted((n for n in METRICS if METRICS.plugin(n).builtin), key=lambda n: METRICS[n].order)
    columns = [f.name for n in names for f in METRICS[n].fields]
    assert len(columns) == len(set(columns)) and not set(columns) & set(IDENTITY)
    always = [f.name for n in names if METRICS[n].always for f in METRICS[n].fields]
    assert always[:4] == ["rho", "t_atk_s", "attack_start_s", "lost_frames"] and always[-1] == "driving_score"
    # Those asked for (cross_traffic: conflict; stale_map: existence; an estimator run by racf serve:
    # service; a supervised one: supervisor) stand in the order their metrics declare; none names a field twice.
    assert [n for n in names if not METRICS[n].always] == ["conflict", "existence", "service", "supervisor"]
    assert ["sign_stands", "needless_stop"] == [f.name for f in METRICS["existence"].fields]


def test_the_supervisor_metric_counts_control_steps_of_every_supervisor_s_columns():
    import pandas as pd

    from racf.experiments.metrics.supervisor import SupervisorMeasures

    log = pd.DataFrame({"control": [True, True, False, True], "sup_safe": [True, False, True, True],
                        "sup_stop": [False, True, True, False], "sup_sign_stop": [True, False, False, False],
                        "sup_bc_outvoted": [False, True, False, False], "sup_sign_outvoted": [False, True, False, True],
                        "sup_eased": [False, False, False, False], "lead_bc_accepted": [0, 3, 4, float("nan")]})
    episode = type("Episode", (), {"log": log})()
    # Control steps only (the third is not one); a step counts once whichever supervisor's column says so.
    assert SupervisorMeasures().score(episode) == {"sup_safe_steps": 2, "sup_stop_steps": 2, "sup_outvoted_steps": 2,
                                                   "sup_eased_steps": 0, "bc_heard": 4}
    assert SupervisorMeasures().score(type("Episode", (), {"log": log[["control"]]})()) == {}
