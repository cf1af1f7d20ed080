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
