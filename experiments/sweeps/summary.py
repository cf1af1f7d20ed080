"""The one summary of a batch of episodes (``docs/protocol.md``), for trials, tables, studies and sweeps.

Per setting: N, then what each metric (``racf.experiments.metrics``) says of its fields. racf's own: SCR with its 95 % Wilson interval; under an attack, ASR = 1 - SCR and the
SCR over the episodes whose attack began before t* (only those can test a defence: where the
sign comes into view inside the braking distance, braking starts before the protocol lets an
attack begin); the trigger delay and the paper's dt_brake over successful stops; failures by
cause; the largest step change of the acted-on distance beyond the car's motion over all
episodes (the no-jump bound); under an attack, the stealth measures (``scoring.stealth``):
the undetected error's median with a 95 % bootstrap interval (seeded: the same rows give the
same interval) and its largest value, the share of episodes whose attack the defence flagged
(Wilson interval) and the median detection delay; the stop rule's STL robustness
(``episode.robustness``): its median with a bootstrap interval, 5th percentile and lowest value,
and the share of episodes that broke the rule (robustness < 0, Wilson interval); each criterion of
the rows' scenarios, a pass rate with its Wilson interval where its rule applies; a scenario's own
metrics (a collision rate, say, or the smallest time-to-collision). A
plug-in metric's fields are summarised by their declared kind (a rate with its Wilson interval, a
median with its bootstrap interval). Strict JSON: None, never NaN.

Rows are grouped by setting and by the scenario's parameters (:func:`setting_key`): a sweep over a
scenario's parameters gives one summary per combination.
"""

from __future__ import annotations

import math

import pandas as pd

from racf.experiments.episode.spec import parse_setting
from racf.experiments.episode.runner import SCENARIO_PREFIX
from racf.experiments.metrics.builtin import robustness_summary, stealth_summary
from racf.experiments.scenarios.base import params_label
from racf.plugins import METRICS, SCENARIOS

__all__ = ["summarize", "summarize_settings", "summarised_metrics", "plugin_measures", "stealth_summary", "robustness_summary",
           "setting_key", "scenario_label", "SCENARIO_PREFIX"]




def summarize(results: pd.DataFrame, attack: bool | None = None) -> dict:
    """The summary of one setting's result rows: N, then each metric's summary
    (``Metric.summarize``) for every registered metric whose fields the rows hold, in the metrics'
    order.

    Args:
        results: result rows (``TrialResult.to_dict()`` and the store's extra columns).
        attack: whether the setting attacks; None reads it from the first row's setting.
    """
    n = int(len(results))
    if attack is None:
        attack = bool(n) and bool(parse_setting(str(results["setting"].iloc[0]))[0])
    summary: dict = {"n": n}
    for metric in summarised_metrics(results):
        summary.update(metric.summarize(results, attack))
    return summary


def summarised_metrics(results: pd.DataFrame) -> list:
    """The metrics every episode has and the others whose fields the rows hold, in the result row's order;
    of those that measure one criterion (``Metric.needs_criterion``), only where a row's scenario judges it
    (rows stored before a measure was dropped from a scenario's rows keep its columns: they are not read)."""
    from racf.experiments.metrics.criteria import scenarios_of

    scenarios = scenarios_of(results) if "target" in results and len(results) else []
    names = [name for name in METRICS if (METRICS[name].always or any(f.name in results for f in METRICS[name].fields))
             and (not scenarios or any(METRICS[name].applies_to(s) for s in scenarios))]
    return [METRICS[name]() for name in sorted(names, key=lambda name: (METRICS[name].order, name))]


def plugin_measures(rows: pd.DataFrame, attacked: bool) -> list[dict]:
    """The card's rows for the plug-in metrics the episodes scored (and racf's own that a scenario
    asks for, such as ``existence``): each summarised field's value
    with its interval and N, as the metric declares it (``Field.summary``, ``Metric.higher_is_better``)."""
    measures = []
    for metric in summarised_metrics(rows):
        if METRICS.plugin(metric.name).builtin and metric.always:
            continue  # racf's own always-scored metrics have their own rows
        summary = metric.summarize(rows, attacked)
        for field in metric.fields:
            if field.summary is None or not summary.get(f"n_{field.name}"):
                continue  # not summarised, or no episode it applies to
            key = f"{field.name}_rate" if field.summary == "rate" else f"{field.name}_median"
            what = "share" if field.summary == "rate" else "median"
            measures.append({"measure": f"{field.name}{' ' + field.unit if field.unit else ''}, {what} ({metric.name})",
                             "value": summary[key], "ci": summary[f"{key}_ci" if field.summary == "rate" else
                                                                  f"{field.name}_ci"],
                             "n": summary[f"n_{field.name}"],
                             "higher_is_better": metric.higher_is_better.get(field.name, True)})
    return measures


def scenario_label(row) -> str:
    """``stale_map[case=removed, shift_m=1.0]``: a row's scenario with its parameter values ('' for a
    scenario without parameters). ``row``: a result row (a dict or a pandas row). A value reads as its
    parameter declares it (a count stays 1 in a column that NaN made float)."""
    target = row.get("target")
    params = {p.name: p for p in SCENARIOS[target].params} if target in SCENARIOS else \
        {str(k)[len(SCENARIO_PREFIX):]: None for k in row.keys() if str(k).startswith(SCENARIO_PREFIX)}
    values = {}
    for name, param in params.items():
        value = row.get(SCENARIO_PREFIX + name)
        if value is None or (isinstance(value, float) and math.isnan(value)):
            continue
        value = value.item() if hasattr(value, "item") else value
        if param is not None and param.type in (int, float) and not isinstance(value, bool):
            value = param.type(value)
        values[name] = value
    return f"{target}[{params_label(values)}]" if values else ""


def setting_key(row) -> str:
    """How summaries name a row's group: its setting, then ``@`` and its scenario with its parameters
    when the scenario has any (``attack@cross_traffic[cars=1, gap_s=0.0, speed=1.0]``)."""
    label = scenario_label(row)
    return f"{row['setting']}@{label}" if label else str(row["setting"])


def summarize_settings(frame: pd.DataFrame) -> dict[str, dict]:
    """:func:`summarize` per setting and scenario parameters (``setting_key``), in sorted order."""
    if frame.empty:
        return {}
    keys = [setting_key(row) for row in frame.to_dict("records")]
    return {key: summarize(rows) for key, rows in frame.groupby(pd.Series(keys, index=frame.index), sort=True)}
