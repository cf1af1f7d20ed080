"""``racf bench service-stress``: fuzzed requests, many connections at once and cars at the control
rate for minutes against a ``racf serve`` process, each with what must hold printed beside it."""

from __future__ import annotations

import argparse
import json

from racf.experiments.cli.common import fail

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    b = sub.add_parser("bench-service-stress", help="racf serve under fuzzed requests, many connections and cars "
                                                    "at the control rate: alive, every answer, memory held",
                       description="Starts a `racf serve` process on a free loopback port and puts it through "
                                   "three trials: --fuzz malformed frame sets (a ping after every batch of 500 must "
                                   "be answered), --connections sockets at once (each answered), and --cars cars "
                                   "at --hz for --seconds replaying an episode's samples (no lost answer, the "
                                   "server's memory within 5 %% of its start). 0 skips a trial.")
    b.add_argument("--defence", default="odca", metavar="NAME", help="the defence the cars use (default odca)")
    b.add_argument("--fuzz", type=int, default=10_000, metavar="N", help="fuzzed frame sets (default 10000)")
    b.add_argument("--connections", type=int, default=200, metavar="K", help="sockets at once (default 200)")
    b.add_argument("--cars", type=int, default=8, metavar="K", help="cars at once (default 8)")
    b.add_argument("--hz", type=float, default=50.0, help="each car's request rate (default 50, the control rate)")
    b.add_argument("--seconds", type=float, default=600.0, help="how long the cars drive (default 600)")
    b.add_argument("--timeout-ms", type=float, default=None, metavar="MS",
                   help="the cars' timeout (default: an episode's)")
    b.add_argument("--seed", type=int, default=0, help="the fuzz's seed (default 0)")
    b.add_argument("--json", action="store_true", help="print one JSON object")
    b.set_defaults(handler=_stress)

    p = sub.add_parser("bench-service-probes", help="an attacker's probes of racf serve, each with its number: "
                                                    "half-sent frames, checkpoint spellings, one host's many "
                                                    "addresses, keep-alives that do no work",
                       description="Starts a `racf serve` process on a free loopback port for each probe: 300 "
                                   "connections that half-send a 1 MiB frame (the server's memory before, with "
                                   "them open and 10 s later), a car served at 50 Hz while another says hello "
                                   "with the shipped head's path spelt 20 ways (its round trips), sessions from "
                                   "64 loopback addresses (whether a car from another range is served), and 100 "
                                   "sessions that only reset beside 100 that only ping past --idle-s 2 (how "
                                   "many hold on).")
    p.add_argument("--service-python", default=None, metavar="PY",
                   help="the Python whose racf serves (default this one): to measure another checkout")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_probes)


def _stress(args: argparse.Namespace) -> int:
    from racf.experiments.episode import TrialSpec
    from racf.experiments.link.wire import DEFAULT_TIMEOUT_MS
    from racf.experiments.service.bench import record_samples
    from racf.experiments.sweeps.service_process import service_process
    from racf.experiments.service.stress import cars, connections, fuzz, ping, rss_mb
    from racf.plugins import ESTIMATORS

    if args.defence not in ESTIMATORS:
        fail("bench service-stress", f"unknown defence {args.defence!r}; registered: {', '.join(ESTIMATORS)}")
    for flag, value in (("--fuzz", args.fuzz), ("--connections", args.connections), ("--cars", args.cars)):
        if value < 0:
            fail("bench service-stress", f"{flag} must be >= 0, got {value}")
    if not (0 < args.hz <= 200 and args.seconds > 0):
        fail("bench service-stress", "--hz must be in (0, 200] and --seconds > 0")
    timeout_ms = args.timeout_ms or DEFAULT_TIMEOUT_MS
    out: dict = {"defence": args.defence}
    with service_process(args.defence) as (endpoint, proc):
        out["endpoint"] = endpoint
        if args.fuzz:
            out["fuzz"] = fuzz(endpoint, args.fuzz, args.seed)
            out["fuzz"]["alive"] = proc.poll() is None and ping(endpoint)
        if args.connections:
            out["connections"] = connections(endpoint, args.connections)
        if args.cars:
            calls, calibration = record_samples(TrialSpec(f"attack+{args.defence}" if args.defence != "raw"
                                                          else "attack", 1, 1.0, 0))
            out["cars"] = cars(endpoint, args.defence, calls, calibration, args.cars, args.hz, args.seconds,
                               timeout_ms, server_pid=proc.pid)
        out["alive"] = proc.poll() is None and ping(endpoint)
        out["server_mb"] = rss_mb(proc.pid)
    if args.json:
        print(json.dumps(out, indent=2, allow_nan=False))
        return 0 if out["alive"] else 1
    print(f"racf serve ({args.defence}) at {out['endpoint']}")
    if "fuzz" in out:
        f = out["fuzz"]
        print(f"fuzz: {f['requests']} malformed frame sets in {f['batches']} batches; a ping answered after "
              f"{f['pings_answered']}/{f['batches']} batches; {f['replies']} error answers; alive: {f['alive']}")
    if "connections" in out:
        c = out["connections"]
        print(f"connections: {c['answered']}/{c['connections']} sockets at once answered")
    if "cars" in out:
        c = out["cars"]
        drift = 100.0 * (c["server_mb_end"] / c["server_mb_start"] - 1.0)
        print(f"cars: {c['cars']} at {c['hz']:g} Hz for {c['seconds']:g} s: {c['steps']} requests, {c['lost']} lost "
              f"(timeout {timeout_ms:g} ms); round trip p50 {c['rtt_p50_ms']:.2f} ms, p99 {c['rtt_p99_ms']:.2f} ms, "
              f"p99.9 {c['rtt_p999_ms']:.2f} ms, max {c['rtt_max_ms']:.2f} ms; "
              f"server memory {c['server_mb_start']:.1f} -> {c['server_mb_end']:.1f} MB ({drift:+.1f} %)")
    print(f"alive at the end: {out['alive']}")
    return 0 if out["alive"] else 1


def _probes(args: argparse.Namespace) -> int:
    from racf.experiments.episode import TrialSpec
    from racf.experiments.service import probes
    from racf.experiments.service.bench import record_samples
    from racf.experiments.sweeps.service_process import service_process

    python, out = args.service_python, {}
    with service_process("raw", python=python) as (endpoint, proc):
        out["half_sent"] = probes.half_sent_memory(endpoint, proc.pid)
    calls, calibration = record_samples(TrialSpec("attack+odca", 1, 1.0, 0))
    with service_process("odca", python=python) as (endpoint, proc):
        out["spellings"] = probes.spellings(endpoint, "odca", calls, calibration)
    with service_process("raw", python=python) as (endpoint, proc):
        out["range"] = probes.range_fill(endpoint)
    with service_process("raw", flags=("--idle-s", "2"), python=python) as (endpoint, proc):
        out["keep_alive"] = probes.keep_alive(endpoint, 2.0)
    if args.json:
        print(json.dumps(out, indent=2, allow_nan=False))
        return 0
    h, sp, r, k = out["half_sent"], out["spellings"], out["range"], out["keep_alive"]
    print(f"half-sent frames: {h['connections']} x {h['frame_bytes']} B: server {h['server_mb_before']:.0f} -> "
          f"{h['server_mb_open']:.0f} MB open -> {h['server_mb_after']:.0f} MB {h['after_s']:.0f} s later; "
          f"{h['closed_by_server']} closed by the server")
    car = sp["served_car"]
    print(f"checkpoint spellings: {sp['spellings']} hellos in {sp['hellos_s']:.2f} s ({sp['answers']}); the served "
          f"car: {car.get('steps')} steps, {car.get('lost')} lost, round trip p99 {car.get('rtt_p99_ms', float('nan')):.1f}"
          f" ms, max {car.get('rtt_max_ms', float('nan')):.1f} ms")
    print(f"one host's addresses: {r['opened']} of {r['asked']} sessions opened from {r['addresses']} addresses in "
          f"{r['seconds']:.1f} s; a car from another range served: {r['other_range_served']}")
    print(f"keep-alives: after {k['after_s']:.0f} s (idle {k['idle_s']:g} s), {k['alive_resetting']} of "
          f"{k['sessions']} resetting and {k['alive_pinging']} of {k['sessions']} pinging still hold a session")
    return 0
