"""``racf trial``, ``racf trials`` (and ``--table``) and ``racf attack-study``: closed-loop episodes."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from racf.experiments.cli.common import (backend_flags, count, fail, fmt_ci, output_dir, plugin_flag, registry_markdown,
                                         registry_rows, sensor_flags)
from racf.experiments.cli.episode_flags import episode_flags, episode_params, trial_flags, trial_spec

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    t = sub.add_parser("trial", help="one closed-loop stop-sign trial: per-step log (Parquet) and result row")
    trial_flags(t)
    t.add_argument("--out", type=output_dir, default=Path("outputs/trial"), help="output folder")
    t.add_argument("--rerun", type=Path, default=None, metavar="PATH",
                   help="also record the episode to a rerun file (.rrd; open it with `racf view PATH`)")
    t.add_argument("--json", action="store_true", help="print the result row as one JSON object instead of a summary")
    t.set_defaults(handler=_trial)

    ts = sub.add_parser("trials", help="a batch of trials over the four signs and speeds 1.0/1.5/2.0 m/s: SCR, latency")
    episode_flags(ts)
    ts.add_argument("--table", action="store_true",
                    help="the paper's table: every setting of TABLE_SETTINGS (clean, clean+odca, attack, attack+odca, "
                         "attack+ekf, attack+chronos, attack+lidar_spoof+odca), N per setting")
    ts.add_argument("--patch", choices=("occlusion", "physical"), default="occlusion",
                    help="with --table: the occluder's table (the paper's, default) or the sticker printed on the "
                         "sign's table (physical_patch on the protocol's schedule and from the episode's start; "
                         "clean, no defence, ODCA, EKF), with the learned detector unless --detector says otherwise")
    ts.add_argument("-n", type=count, default=30, help="number of trials (default 30; 12 cover every sign x speed)")
    ts.add_argument("--seed", type=int, default=0, help="seed of the first trial; trial i uses seed + i")
    backend_flags(ts)
    ts.add_argument("--out", type=output_dir, default=None,
                    help="output folder (default outputs/trials/<setting>, outputs/table with --table); finished "
                         "trials there are reused (their ids hash the spec, configs and code version)")
    ts.add_argument("--json", action="store_true", help="print one JSON summary object instead of tables")
    ts.add_argument("--rerun", action="store_true",
                    help="also record every trial that runs to rerun: <out>/trials/<trial_id>.rrd (`racf view`)")
    ts.set_defaults(handler=_trials)

    st = sub.add_parser("attack-study", help="no-defence patch attack tables: persistence, coverage, strong regime")
    st.add_argument("studies", nargs="*", default=None, metavar="STUDY",
                    help="persistence, coverage and/or strong (default all three)")
    st.add_argument("-n", type=count, default=24,
                    help="trials per table row (default 24; the strong row uses max(n, 30))")
    st.add_argument("--seed", type=int, default=0)
    sensor_flags(st)
    backend_flags(st)
    st.add_argument("--out", type=output_dir, default=Path("outputs/attack_study"),
                    help="output folder (trials are reused)")
    st.add_argument("--json", action="store_true", help="print one JSON object instead of tables")
    st.set_defaults(handler=_attack_study)

    ls = sub.add_parser("list", help="the registered attacks, estimators (defences), detectors, scenarios (with "
                                     "their parameters) and metrics (with their fields), plug-ins included")
    ls.add_argument("kind", nargs="?", choices=LIST_KINDS, metavar="KIND",
                    help=f"list only one kind: {', '.join(LIST_KINDS)} (default: all)")
    ls.add_argument("--markdown", action="store_true", help="print the README's Markdown tables")
    ls.add_argument("--json", action="store_true", help="print {kind: {name: {origin, description}}} as JSON")
    plugin_flag(ls)
    ls.set_defaults(handler=_list)


def _trial(args: argparse.Namespace) -> int:
    from racf.provenance import atomic_write

    spec = trial_spec(args, "trial")
    from racf.errors import EpisodeFailed
    from racf.experiments.episode.preflight import check_specs
    from racf.experiments.sweeps.failures import LOG_NAME, append_log, describe
    from racf.experiments.episode.rerun_log import recorded_trial

    check_specs([spec])
    try:
        result, log = recorded_trial(spec, args.rerun, f"racf trial {spec.trial_id}")
    except Exception as err:  # the episode's code raised: one line naming the part, the traceback in a log
        failure = describe(spec, err)
        append_log(args.out, failure, first=True)
        raise EpisodeFailed([failure], 0, 1, args.out / LOG_NAME) from None
    args.out.mkdir(parents=True, exist_ok=True)
    log_path = atomic_write(args.out / f"{spec.trial_id}.parquet", log)
    atomic_write(args.out / f"{spec.trial_id}.json", json.dumps(result.to_dict(), indent=2, allow_nan=False))
    row = result.to_dict()
    if args.json:
        print(json.dumps({**row, "log": str(log_path)}, allow_nan=False))
    else:
        print(trial_summary(row, log_path, args.out / f"{spec.trial_id}.json"))
    if row.get("service_fallback"):  # said where it is read, not only in a field
        print(f"racf trial: the defence service gave no answer the car could act on, on "
              f"{row['service_fallback_steps']} of {row['service_fallback_steps'] + row['service_steps']} steps; the car drove on "
              f"{_fallback_words(row)} there ({row['service_invalid']} answers refused by the protocol's check, "
              f"{row['service_restarts']} defence restarts, {row['service_new_sessions']} new sessions)",
              file=sys.stderr)
    return 0


#: What names the trial (its header line), not what it measured.
_IDENTITY = ("trial_id", "setting", "estimator", "target", "sign", "speed", "seed")


def trial_summary(row: dict, log: Path, result: Path) -> str:
    """One trial's result for a reader: what ran, then each measure it has (those it has not are
    left out), then where its log and its full row are."""
    from racf.experiments.episode.criteria import verdict_line
    from racf.plugins import SCENARIOS

    criteria = SCENARIOS[row["target"]].criteria if row["target"] in SCENARIOS else ()
    verdict = verdict_line(row, criteria) or "no criterion applied"
    # What protected the car: a supervised episode scores the supervisor metric.
    setting = f"{row['setting']}+supervisor" if "sup_stop_steps" in row else row["setting"]
    head = (f"racf trial: {setting} on {row['target']} {row['sign']} at {row['speed']:g} m/s, seed "
            f"{row['seed']}: {verdict}")
    shown = {k: v for k, v in row.items() if k not in _IDENTITY and k not in ("success", "failure") and v is not None}
    width = max(map(len, shown), default=0)
    meanings = _field_meanings() | {c.name: f"the criterion: {c.checks}" for c in criteria}
    values = {k: f"{v:.3g}" if isinstance(v, float) else str(v) for k, v in shown.items()}
    room = max(map(len, values.values()), default=0)
    body = [f"  {k.ljust(width)}  {values[k].ljust(room)}  {meanings.get(k, '')}".rstrip() for k in shown]
    return "\n".join([head, *body, f"log: {log}; row: {result} (--json prints it); every field: {GLOSSARY}"])


#: Where every field of the result row is explained.
GLOSSARY = "docs/reference/step-log.md#the-result-row"


def _field_meanings() -> dict[str, str]:
    """Each registered metric's fields, by name: unit and meaning, as the glossary gives them."""
    from racf.plugins import METRICS

    out = {}
    for name in METRICS:
        for f in METRICS[name].fields:
            out.setdefault(f.name, f"({f.unit}) {f.meaning}" if f.unit else f.meaning)
    return out


def _trials(args: argparse.Namespace) -> int:
    from racf.experiments.sweeps.batches import batch_specs, run_batch, run_table
    from racf.experiments.sweeps.summary import summarize

    where = {"workers": args.workers, "backend": args.backend, "address": args.address}
    if args.table:
        from racf.experiments.sweeps.batches import TABLES

        _, params = episode_params(args, "trials", table=True)
        physical = args.patch == "physical"
        if physical and args.detector is None:
            params["detector"] = "learned"
        out = args.out or Path("outputs/table" + ("-physical" if physical else ""))
        try:
            table = run_table(args.n, out, seed=args.seed, progress=not args.json, rerun=args.rerun,
                              rows=TABLES[args.patch], **where, **params)
        except ValueError as err:
            fail("trials", str(err))
        if args.json:
            print(json.dumps({"sensor_profile": args.sensor_profile, "sign_geometry": args.sign_geometry,
                              "detector": params["detector"], "patch": args.patch, "settings": table},
                             allow_nan=False))
        else:
            print(f"sensor profile {args.sensor_profile}, stop signs {args.sign_geometry}, "
                  f"detector {params['detector']}, patch {args.patch}")
            print(table_text(table))
        return 0
    if args.patch != "occlusion":
        fail("trials", "--patch chooses a --table; without --table give the setting (e.g. clean+physical_patch)")
    setting, params = episode_params(args, "trials")
    try:
        specs = batch_specs(setting, args.n, args.seed, **params)
    except ValueError as err:
        fail("trials", str(err))
    out = args.out or Path("outputs/trials") / setting
    results = run_batch(specs, out, progress=not args.json, rerun=args.rerun, **where)
    summary = summarize(results)
    if args.json:
        print(json.dumps(summary, allow_nan=False))
        return 0
    print(f"{'sign':>4} {'speed':>6} {'N':>3} {'SCR':>5} {'dt_brake s (mean +- std)':>26}  failures")
    for (sign_, speed_), group in results.groupby(["sign", "speed"]):
        lat = group.loc[group["success"], "dt_brake_s"].astype(float).dropna()
        lat_text = f"{lat.mean():.3f} +- {lat.std(ddof=1) if len(lat) > 1 else 0:.3f}" if len(lat) else "-"
        failures = ", ".join(f"{k} {v}" for k, v in group["failure"].dropna().value_counts().items()) or "-"
        print(f"{sign_:>4} {speed_:>6.1f} {len(group):>3} {group['success'].mean():>5.2f} {lat_text:>26}  {failures}")
    print(table_text({setting: summary}, results))
    if "service_fallback" in results and results["service_fallback"].astype(bool).any():
        fell = results[results["service_fallback"].astype(bool)]
        counts = ", ".join(f"{int(fell[c].sum())} {words}" for c, words in (
            ("service_invalid", "answers refused by the protocol's check"), ("service_restarts", "defence restarts"),
            ("service_new_sessions", "new sessions")) if c in fell)
        print(f"the defence service gave no answer the car could act on in {len(fell)} of {len(results)} episodes "
              f"({int(fell['service_fallback_steps'].sum())} steps, {int(fell['service_onboard_steps'].sum())} of them on "
              f"its onboard defence; {counts}): the car drove on its fallback there")
    print(f"results: {out / 'results.parquet'}; per-step logs: {out / 'trials'}")
    return 0


def table_text(table: dict[str, dict], frame=None) -> str:
    """SCR / ASR with Wilson intervals, trigger delay and dt_brake over successes, failures by cause;
    then what each scenario of ``frame``'s rows adds (``Scenario.report``)."""
    from racf.experiments.metrics.criteria import scenarios_of
    from racf.experiments.sweeps.batches import PAPER_TABLE

    def ms(mean, std):
        return "-" if mean is None else f"{mean:.3f} +- {std or 0:.3f}"

    lines = [f"{'setting':<32}{'N':>4}{'SCR [95% Wilson]':>20}{'ASR [95% Wilson]':>20}{'trigger delay s':>18}"
             f"{'dt_brake s':>18}{'n':>4}{'SCR, attack before t*':>28}  failures"]
    for name, r in table.items():
        asr = f"{r['asr']:.2f} {fmt_ci(*r['asr_ci'])}" if r.get("asr") is not None else "-"
        fails = ", ".join(f"{k} {v}" for k, v in r["failures"].items() if v) or "-"
        early = "-" if r.get("scr_attack_before_t_star") is None else (
            f"{r['scr_attack_before_t_star']:.2f} {fmt_ci(*r['scr_attack_before_t_star_ci'])} "
            f"({r['n_attack_before_t_star']})")
        lines.append(f"{name:<32}{r['n']:>4}{r['scr']:>6.2f} {fmt_ci(*r['scr_ci']):>13}{asr:>20}"
                     f"{ms(r['trigger_delay_mean'], r['trigger_delay_std']):>18}"
                     f"{ms(r['dt_brake_mean'], r['dt_brake_std']):>18}{r['n_latency']:>4}{early:>28}  {fails}")
    for scenario in scenarios_of(frame) if frame is not None else ():  # each scenario's own table, as a sweep's report has it
        lines += scenario().report(frame, table)[0]
    paper = "; ".join(f"{name} SCR {p['scr']:.2f}, dt {p['dt_brake_s']:.3f} s"
                      for name, p in PAPER_TABLE["rows"].items())
    lines.append("trigger delay = t(brake) - t*; dt_brake = t* to braking within 0.60 m of the line (the paper's "
                 "latency); both over successful stops (n). SCR, attack before t*: the trials whose attack began "
                 f"before t* (their count). Paper ({PAPER_TABLE['platform']}, N = {PAPER_TABLE['n']}): {paper}")
    return "\n".join(lines)


def _attack_study(args: argparse.Namespace) -> int:
    from racf.experiments.sweeps.studies import STUDIES, run_study

    names = list(dict.fromkeys(args.studies or STUDIES))
    unknown = [n for n in names if n not in STUDIES]
    if unknown:
        fail("attack-study", f"unknown study {unknown}; choose from {', '.join(STUDIES)}")
    tables = {name: run_study(name, args.n, args.out, seed=args.seed, workers=args.workers, progress=not args.json,
                              backend=args.backend, address=args.address, sensor_profile=args.sensor_profile,
                              sign_geometry=args.sign_geometry) for name in names}
    if args.json:
        print(json.dumps(tables))
        return 0
    for name, rows in tables.items():
        print(f"\n{name} (no defence)")
        print(f"{'setting':<42}{'N':>4}{'lost frames':>13}{'ASR [95% Wilson]':>22}{'SCR':>6}{'dt_brake s':>18}")
        for r in rows:
            lat = (f"{r['dt_brake_mean']:.2f} +- {r['dt_brake_std'] or 0:.2f} ({r['n_latency']})"
                   if r["n_latency"] else "-")
            print(f"{r['label']:<42}{r['n']:>4}{r['lost_frames_mean']:>13.1f}"
                  f"{r['asr']:>8.2f} {fmt_ci(*r['asr_ci']):>13}{r['scr']:>6.2f}{lat:>18}")
    print(f"\ntrials and logs under {args.out}")
    return 0


#: What ``racf list KIND`` lists.
LIST_KINDS = ("attacks", "estimators", "detectors", "scenarios", "metrics", "stages")


def _list(args: argparse.Namespace) -> int:
    from racf.plugins import ATTACKS, CAR_STAGES, DETECTORS, ESTIMATORS, METRICS, REGISTRIES, SCENARIOS

    if args.markdown:
        print(registry_markdown())
        return 0
    if args.json:
        listed = {kind: {name: {"origin": registry.plugin(name).origin, "description": text}
                         for name, text in registry_rows(registry)} for kind, registry in REGISTRIES.items()}
        for name, entry in listed["scenario"].items():
            entry["params"] = {p.name: {"default": p.default, "low": p.low, "high": p.high, "choices": p.choices,
                                        "unit": p.unit, "meaning": p.meaning} for p in SCENARIOS[name].params}
            entry["criteria"] = {c.name: {"checks": c.checks, "penalty": c.penalty, "terminates": c.terminates}
                                 for c in SCENARIOS[name].criteria}
        for name, entry in listed["metric"].items():
            entry["always"] = METRICS[name].always
            entry["fields"] = {f.name: {"unit": f.unit, "meaning": f.meaning, "summary": f.summary}
                               for f in METRICS[name].fields}
        listed["broken"] = {kind: dict(registry.broken) for kind, registry in REGISTRIES.items() if registry.broken}
        print(json.dumps(listed, default=str))
        return 0
    shown = {args.kind} if args.kind else set(LIST_KINDS)
    for kind, title, registry in (("attacks", "attacks (--attack, joined by ',' or '+')", ATTACKS),
                                  ("estimators", "estimators (--estimator)", ESTIMATORS),
                                  ("detectors", "detectors (--detector)", DETECTORS),
                                  ("stages", "car stages (a scenario's mission engages them)", CAR_STAGES)):
        if kind in shown:
            print(title)
            for name, text in registry_rows(registry):
                origin = registry.plugin(name).origin
                print(f"  {name:<24}{text}" + ("" if origin == "racf" else f"  [plug-in: {origin}]"))
    if "scenarios" in shown:
        print("scenarios (--target; parameters: --scenario-param KEY=VALUE)")
        for name, text in registry_rows(SCENARIOS):
            origin = SCENARIOS.plugin(name).origin
            print(f"  {name:<24}{text}" + ("" if origin == "racf" else f"  [plug-in: {origin}]"))
            for param in SCENARIOS[name].params:
                print(f"    {param.describe()}")
            for criterion in SCENARIOS[name].criteria:
                print(f"    criterion {criterion.name}: {criterion.checks} (fails: x {criterion.penalty}"
                      f"{', ends the episode' if criterion.terminates else ''})")
    if "metrics" in shown:
        print("metrics (every episode; --metric NAME for those marked 'asked')")
        for name, text in registry_rows(METRICS):
            origin = METRICS.plugin(name).origin
            print(f"  {name:<24}{text}" + ("" if METRICS[name].always else "  [asked]")
                  + ("" if origin == "racf" else f"  [plug-in: {origin}]"))
            print(f"    fields: {', '.join(f.name + (f' ({f.unit})' if f.unit else '') for f in METRICS[name].fields)}")
    broken = [(kind, name, why) for kind, registry in REGISTRIES.items() for name, why in registry.broken.items()]
    if broken:
        print("broken plug-ins (installed, failed to load: left out)")
        for kind, name, why in broken:
            print(f"  {kind} {name}: {why}")
    return 0


def _fallback_words(row: dict) -> str:
    """What drove the car where the service did not: its onboard defence, its own depth, or both."""
    onboard, steps = row.get("service_onboard_steps", 0), row["service_fallback_steps"]
    if onboard == steps:
        return "its onboard defence"
    return "its own depth distance" if not onboard else f"its onboard defence ({onboard} steps) and its own depth"
