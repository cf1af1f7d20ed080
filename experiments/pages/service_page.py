"""The speed page's section on ROS 2 bags and the defence service: the cost of exporting and
replaying a drive, the service's round trip per step, and the paper's table through the service
beside the in-process one."""

from __future__ import annotations

import math

from racf.experiments.pages.results_format import meta_lines, missing

__all__ = ["bags_and_service_markdown", "table_differences", "probes_markdown", "PROBES_COMMAND"]

PROBES_COMMAND = "racf bench-service-probes --json (and --service-python PY for the code before)"


def _flat(value, prefix: str = "") -> dict:
    """Nested numbers as {dotted key: value}."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            out |= _flat(v, f"{prefix}{k}.")
        return out
    if isinstance(value, list):
        out = {}
        for i, v in enumerate(value):
            out |= _flat(v, f"{prefix}{i}.")
        return out
    return {prefix[:-1]: value}


def table_differences(in_process: dict, served: dict) -> tuple[int, list[str]]:
    """How many values the two tables' settings hold (the service's own fields left out), and the
    keys whose values differ."""
    a = _flat(in_process["settings"])
    b = {k: v for k, v in _flat(served["settings"]).items() if "service" not in k}
    keys = sorted(set(a) | set(b))
    differ = [k for k in keys if not (a.get(k) == b.get(k) or (isinstance(a.get(k), float) and isinstance(b.get(k), float)
                                                                and math.isnan(a[k]) and math.isnan(b[k])))]
    return len(keys), differ


def served_table(local: dict, served: dict, how: str) -> list[str]:
    """The paper's table through the service (over ``how``) beside the in-process one."""
    n, differ = table_differences(local, served)
    lines = [f"The paper's table through the service (`racf serve` on {how}) against the stored in-process table:", ""]
    lines += meta_lines(served["meta"])
    lines += ["| setting | N | SCR in process | SCR through the service | steps served | median round trip ms "
              "| worst p99 ms | late steps | fallback steps |", "|---|---|---|---|---|---|---|---|---|"]
    for name, row in served["settings"].items():
        mine = local["settings"].get(name, {})
        t = served.get("service", {}).get(name, {})
        lines.append(f"| {name} | {row['n']} | {mine.get('scr', float('nan')):.2f} | {row['scr']:.2f} | "
                     f"{t.get('steps', '-')} | {t.get('rtt_p50_ms_median', float('nan')):.2f} | "
                     f"{t.get('rtt_p99_ms_max', float('nan')):.2f} | {t.get('late_steps', '-')} | "
                     f"{t.get('fallback_steps', '-')} |")
    late = sum(t.get("late_steps", 0) for t in served.get("service", {}).values())
    steps = sum(t.get("steps", 0) for t in served.get("service", {}).values())
    scr_moved = [k for k in differ if k.endswith(".scr")]
    lines += ["", f"Of the {n} values of the two tables (every setting's rates, intervals, latencies and robustness), "
              + (f"all {n} are equal." if not differ else
                 f"{n - len(differ)} are equal and {len(differ)} differ: " + ", ".join(f"`{k}`" for k in differ[:12])
                 + f". {late} of the {steps} answers came later than the 20 ms control period, and the measured "
                   "latency delayed those actions by a step: the differences are theirs"
                 + ("; no SCR moved." if not scr_moved else f"; SCR moved in {len(scr_moved)} settings.")), ""]
    return lines


def bags_and_service_markdown(d) -> list[str]:
    lines = ["## ROS 2 bags and the defence service", ""]
    if "bench-bags" in d:
        b = d["bench-bags"]
        lines += ["Exporting a drive as a bag (the episode run again, every reading written) and replaying the car's "
                  "software on it, on one core (`taskset -c 0`), against the episode alone:", ""]
        lines += meta_lines(b["meta"]) + ["| step | wall s | s per simulated s |", "|---|---|---|"]
        for key in ("episode", "export", "replay"):
            lines.append(f"| {key} | {b[key + '_s']:.1f} | {b[key + '_per_simulated_s']:.2f} |")
        lines += ["", f"A {b['simulated_s']:.1f} s drive ({b['steps']} steps, `{b['spec']}`), a {b['bag_megabytes']} MB "
                  f"bag; the replay gives back the episode's distances, brakes and detections: {b['replay_equal']}.", ""]
    else:
        lines += missing("bench-bags", "taskset -c 0 racf bench bags --json")
    if "bench-service" in d:
        s = d["bench-service"]
        rt, local = s["round_trip"], s["in_process"]
        lines += [f"The defence service's round trip per step (`racf serve` on loopback, {s['defence']}, the samples "
                  "of one attacked approach sent over and over), against the same estimate in the car's process:", ""]
        lines += meta_lines(s["meta"]) + ["| | N | p50 ms | p90 ms | p99 ms | p99.9 ms | max ms |",
                                          "|---|---|---|---|---|---|---|"]
        for name, row in (("round trip through the service", rt), ("the estimate in the car's process", local)):
            lines.append(f"| {name} | {row['n']} | {row['p50_ms']:.3f} | {row['p90_ms']:.3f} | {row['p99_ms']:.3f} | "
                         f"{row['p999_ms']:.3f} | {row['max_ms']:.3f} |")
        lines += ["", f"The paper's offboard cycle (perception, transmission, ODCA inference and control): about "
                  f"{s['paper_cycle_ms']:.0f} ms. Distances that differed from the car's own: {s['distance_mismatches']}.", ""]
    else:
        lines += missing("bench-service", "racf bench service -n 10000 --json")
    for name, how in (("closed-loop-table-service", "a plain link"), ("closed-loop-table-curve", "a CurveZMQ link")):
        if name in d and "closed-loop-table" in d:
            lines += served_table(d["closed-loop-table"], d[name], how)
        else:
            lines += missing(name, "racf trials --table -n 30 --json --estimator-endpoint ..."
                             + (" --service-keys DIR" if "curve" in name else ""))
    lines += link_markdown(d)
    return lines


def link_markdown(d) -> list[str]:
    """The service under stress, CurveZMQ's cost, and ODCA onboard (issue 58)."""
    lines: list[str] = []
    if "service-stress" in d:
        s = d["service-stress"]
        f, c, cars = s["fuzz"], s["connections"], s["cars"]
        drift = 100.0 * (cars["server_mb_end"] / cars["server_mb_start"] - 1.0)
        lines += ["No message stops the service: `racf serve` (a separate process) under malformed requests, many "
                  "connections at once and cars at the control rate:", ""]
        lines += meta_lines(s["meta"]) + ["| trial | N | what must hold | measured |", "|---|---|---|---|"]
        lines += [f"| fuzzed frame sets (any frames, any payload, broken requests) | {f['requests']} | a ping answered "
                  f"after every batch | {f['pings_answered']} of {f['batches']} batches; alive: {f['alive']} |",
                  f"| connections at once, one ping each | {c['connections']} | each answered | {c['answered']} |",
                  f"| cars at {cars['hz']:g} Hz for {cars['seconds']:g} s | {cars['steps']} requests from {cars['cars']} "
                  f"cars | no lost answer; memory within 5 % | {cars['lost']} lost; {cars['server_mb_start']:.1f} -> "
                  f"{cars['server_mb_end']:.1f} MB ({drift:+.1f} %) |", "",
                  f"The cars' round trips: p50 {cars['rtt_p50_ms']:.2f} ms, p99 {cars['rtt_p99_ms']:.2f} ms, p99.9 "
                  f"{cars['rtt_p999_ms']:.2f} ms, longest {cars['rtt_max_ms']:.2f} ms (8 cars are threads of one "
                  "process on 2 cores beside the server).", ""]
    else:
        lines += missing("service-stress", "racf bench service-stress --json")
    lines += probes_markdown(d)
    if "bench-service-curve" in d and "bench-service" in d:
        plain, curve = d["bench-service"]["round_trip"], d["bench-service-curve"]["round_trip"]
        lines += ["CurveZMQ's cost on the round trip (the same samples, a fresh service each; authentication once per "
                  "connection, then about 33 bytes and a box per message):", ""]
        lines += meta_lines(d["bench-service-curve"]["meta"]) + ["| link | N | p50 ms | p99 ms | max ms |",
                                                                 "|---|---|---|---|---|"]
        for name, row in (("plain", plain), ("CurveZMQ", curve)):
            lines.append(f"| {name} | {row['n']} | {row['p50_ms']:.3f} | {row['p99_ms']:.3f} | {row['max_ms']:.3f} |")
        lines.append("")
    else:
        lines += missing("bench-service-curve", "racf bench service --curve -n 10000 --json")
    if "odca-onboard" in d:
        o = d["odca-onboard"]
        lines += ["ODCA onboard: the prior and the head exported to ONNX (`racf odca export`) and run by onnxruntime on "
                  "one thread, against the PyTorch path, step by step over the offline benchmark's test series:", ""]
        lines += meta_lines(o["meta"])
        lines += [f"Largest difference in the repaired distance over {o['steps']} steps ({o['series']} runs, clean and "
                  f"the three presets): {o['max_abs_diff_m']:.1e} m; steps where the gate chose another source: "
                  f"{o['source_changes']}.", "", "| one thread | p50 ms | p99 ms | max ms | steps over the 20 ms period |",
                  "|---|---|---|---|---|"]
        for name, label in (("torch", "PyTorch (the prior traced, the head in numpy)"), ("onnx", "onnxruntime (onboard)")):
            row = o["latency"][name]
            lines.append(f"| {label} | {row['p50_ms']:.3f} | {row['p99_ms']:.3f} | {row['max_ms']:.2f} | "
                         f"{row['over_period']} |")
        lines.append("")
    else:
        lines += missing("odca-onboard", "racf bench odca-onboard --json")
    if "closed-loop-table-onnx" in d and "closed-loop-table" in d:
        onboard, local = d["closed-loop-table-onnx"], d["closed-loop-table"]
        n, differ = table_differences(local, onboard)
        lines += ["The paper's table with ODCA onboard (`--estimator-option odca.runtime=onnx`) against the stored "
                  "table with ODCA in PyTorch:", ""]
        lines += meta_lines(onboard["meta"]) + ["| setting | N | SCR, PyTorch | SCR, onnxruntime |", "|---|---|---|---|"]
        for name, row in onboard["settings"].items():
            lines.append(f"| {name} | {row['n']} | {local['settings'].get(name, {}).get('scr', float('nan')):.2f} | "
                         f"{row['scr']:.2f} |")
        lines += ["", f"Of the {n} values of the two tables, " + (f"all {n} are equal." if not differ else
                  f"{n - len(differ)} are equal and {len(differ)} differ: " + ", ".join(f"`{k}`" for k in differ[:12])
                  + "."), ""]
    else:
        lines += missing("closed-loop-table-onnx", "racf trials --table -n 30 --json --estimator-option odca.runtime=onnx")
    lines += ["The `racf-link` battery (the paper's offboard loop, its link delayed, lost and spoofed, on a plain and "
              "on a CurveZMQ link) is on [the leaderboard](leaderboard.md).", ""]
    return lines


def probes_markdown(d) -> list[str]:
    """An attacker's probes of the service (issue 79), on the code before the fix and after it."""
    if "service-probes" not in d:
        return missing("service-probes", PROBES_COMMAND)
    data = d["service-probes"]
    lines = ["What the network could cost the service, probed as an attacker would (every target on loopback), on "
             f"the code before issue 79 ({data['meta'].get('before', '?')}) and after it:", ""]
    lines += meta_lines(data["meta"]) + ["| probe | before | after |", "|---|---|---|"]
    b, a = data["before"], data["after"]

    def half(h):
        return (f"{h['server_mb_before']:.0f} -> {h['server_mb_open']:.0f} MB open -> {h['server_mb_after']:.0f} MB "
                f"{h['after_s']:.0f} s later; {h['closed_by_server']} of {h['connections']} closed by the service")

    def spelt(s):
        car = s["served_car"]
        return (f"{s['spellings']} hellos in {s['hellos_s']:.2f} s ({', '.join(f'{n} {k}' for k, n in sorted(s['answers'].items()))}); "
                f"the served car lost {car['lost']} of {car['steps']} steps")

    def ranged(r):
        return (f"{r['opened']} of {r['asked']} sessions opened; a car from another range served: "
                f"{'yes' if r['other_range_served'] else 'no'}")

    def kept(k):
        return (f"{k['alive_resetting']} of {k['sessions']} resetting and {k['alive_pinging']} of {k['sessions']} pinging "
                f"hold a session {k['after_s']:.0f} s on (idle {k['idle_s']:g} s)")

    for title, key, words in (("300 connections half-sending a 1 MiB frame", "half_sent", half),
                              ("a car served at 50 Hz while another names the shipped head 20 ways", "spellings", spelt),
                              ("64 loopback addresses, 16 hellos each", "range", ranged),
                              ("100 sessions that only reset, 100 that only ping", "keep_alive", kept)):
        lines.append(f"| {title} | {words(b[key])} | {words(a[key])} |")
    return lines + ["", "The served car's lost steps after the fix are the machine's load (two sweeps and two mutation "
                        "runs shared its 2 cores): its hellos were refused in milliseconds.", ""]
