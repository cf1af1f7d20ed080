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
and the share of episodes that broke the rule (robustness < 0, Wilson interval); with
cross-traffic (``episode.conflict``), the collision rate (Wilson interval; under an attack also
over the episodes whose attack began before t*), the conflict outcomes and the smallest
time-to-collision. A plug-in metric's fields are summarised by their declared kind (a rate with its
Wilson interval, a median with its bootstrap interval). Strict JSON: None, never NaN.
"""

from __future__ import annotations

import pandas as pd

from racf.experiments.episode.spec import parse_setting
from racf.experiments.metrics.builtin import conflict_summary, robustness_summary, stealth_summary
from racf.plugins import METRICS

__all__ = ["summarize", "summarize_settings", "summarised_metrics", "plugin_measures", "stealth_summary", "robustness_summary",
           "conflict_summary", "setting_key"]


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
    """The metrics every episode has and the others whose fields the rows hold, in the result row's order."""
    names = [name for name in METRICS if METRICS[name].always or any(f.name in results for f in METRICS[name].fields)]
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


def setting_key(setting: str, traffic_cars: int = 0) -> str:
    """How summaries name a setting: with other cars, ``SETTING@trafficN``."""
    return f"{setting}@traffic{int(traffic_cars)}" if traffic_cars else str(setting)


def summarize_settings(frame: pd.DataFrame) -> dict[str, dict]:
    """:func:`summarize` per setting (and per traffic, ``setting_key``), in sorted order."""
    if frame.empty:
        return {}
    cars = pd.to_numeric(frame["traffic_cars"], errors="coerce").fillna(0).astype(int) if "traffic_cars" in frame \
        else pd.Series(0, index=frame.index)
    keys = [setting_key(s, c) for s, c in zip(frame["setting"], cars)]
    return {key: summarize(rows) for key, rows in frame.groupby(pd.Series(keys, index=frame.index), sort=True)}
