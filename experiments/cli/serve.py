"""``racf serve``: a defence as its own process; ``racf bench service``: its round trip per step."""

from __future__ import annotations

import argparse
import json
import sys

from racf.experiments.cli.common import estimator_help, estimator_option_flag, estimator_options, fail, plugin_flag

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("serve", help="serve defences (estimators) to cars over ZeroMQ: trials, sweeps and scorecards "
                                     "reach them with --estimator-endpoint; `racf serve keys DIR` makes CurveZMQ keys",
                       description="Runs the defences in this process, one instance per connecting car, behind "
                                   "a ZeroMQ socket (msgpack requests, numpy arrays as raw buffers). Episodes "
                                   "reach it with --estimator-endpoint and name their defence; Ctrl-C stops it. "
                                   "With --keys the link is CurveZMQ: the cars pin this service's key and only "
                                   "the admitted cars are answered (required beyond loopback).")
    s.add_argument("--defence", action="append", default=None, metavar="NAME",
                   help=f"serve only this defence (repeatable; default: every registered one): {estimator_help()}")
    s.add_argument("--bind", default="tcp://127.0.0.1:5555", metavar="tcp://HOST:PORT",
                   help="where to listen (default tcp://127.0.0.1:5555; port 0: any free port, printed)")
    s.add_argument("--keys", default=None, metavar="DIR",
                   help="serve over CurveZMQ with the keys of `racf serve keys DIR`: its key pair, and the cars "
                        "admitted in DIR/admitted (required when --bind is not loopback)")
    s.add_argument("--insecure", action="store_true",
                   help="serve a non-loopback address without keys: anyone on the network may ask, and anyone "
                        "between may answer")
    s.add_argument("--idle-s", type=float, default=600.0, metavar="S",
                   help="drop a car's session whose defence did no work this long (default 600; a reset or a "
                        "ping is no work); a session also ends when its car's connection closes")
    s.add_argument("--sessions-per-client", type=int, default=16, metavar="N",
                   help="at most N sessions per car key (CurveZMQ) or address (plain link); a hello beyond is "
                        "refused, and no car's session is ended for it (default 16)")
    s.add_argument("--sessions-per-range", type=int, default=64, metavar="N",
                   help="at most N sessions per network range of the cars' addresses (an IPv4 /24, an IPv6 /64): "
                        "one host holds many addresses (default 64)")
    s.add_argument("--max-sessions", type=int, default=1024, metavar="N",
                   help="at most N sessions in all; a hello beyond is refused (default 1024)")
    estimator_option_flag(s)
    plugin_flag(s)
    s.set_defaults(handler=_serve)
    inner = s.add_subparsers(dest="serve_command", required=False, metavar="[keys]")
    k = inner.add_parser("keys", help="make the service's and the cars' CurveZMQ key pairs",
                         description="Writes DIR/server.key (every car pins it), DIR/server.key_secret (the "
                                     "service's), DIR/cars/NAME.key_secret (each car's) and DIR/admitted/NAME.key "
                                     "(the cars the service admits). Nothing is overwritten.")
    k.add_argument("dir", metavar="DIR", help="the key folder to write")
    k.add_argument("--car", action="append", default=None, metavar="NAME",
                   help="a car to make a pair for (repeatable; default: one car named 'car')")
    k.set_defaults(handler=_keys)

    b = sub.add_parser("bench-service", help="the defence service's round trip per step on real samples, "
                                             "beside the in-process cost and the paper's 49 ms cycle")
    b.add_argument("--defence", default="odca", metavar="NAME", help="the defence to serve (default odca)")
    b.add_argument("-n", type=int, default=10_000, help="steps to time (default 10000)")
    b.add_argument("--endpoint", default=None, metavar="tcp://HOST:PORT",
                   help="a running `racf serve` (default: start one on a free loopback port)")
    b.add_argument("--sign", type=int, default=1, help="the stop sign of the episode whose samples are sent (default 1)")
    b.add_argument("--setting", default=None, help="that episode's setting (default attack+DEFENCE)")
    b.add_argument("--curve", action="store_true",
                   help="over CurveZMQ: the started service with fresh keys, the car pinning them")
    b.add_argument("--json", action="store_true", help="print one JSON object")
    estimator_option_flag(b)
    b.set_defaults(handler=_bench)


def _serve(args: argparse.Namespace) -> int:
    import logging

    from racf.experiments.link.curve import ServerKeys, is_loopback
    from racf.experiments.service.server import serve
    from racf.experiments.service.sessions import Sessions
    from racf.plugins import ESTIMATORS

    names = tuple(dict.fromkeys(args.defence)) if args.defence else None
    unknown = [d for d in names or () if d not in ESTIMATORS]
    if unknown:
        fail("serve", f"unknown defence {unknown[0]!r}; registered: {', '.join(ESTIMATORS)}")
    if args.estimator_option and not names:
        fail("serve", "--estimator-option sets the options of a defence this service runs: name it with --defence")
    # The operator's options, the only ones a car may ask for (a bare KEY: the first defence's).
    chosen = estimator_options("serve", args.estimator_option, names, names[0]) if names else {}
    offers = {name: chosen.get(name, {}) for name in names} if names else None
    if args.keys is None and not is_loopback(args.bind) and not args.insecure:
        fail("serve", f"{args.bind} is reachable from other machines: serve it with --keys DIR (make them with "
                      f"`racf serve keys DIR`), or say --insecure")
    for flag, value, lo in (("--idle-s", args.idle_s, 1.0), ("--sessions-per-client", args.sessions_per_client, 1),
                            ("--sessions-per-range", args.sessions_per_range, 1), ("--max-sessions", args.max_sessions, 1)):
        if value < lo:
            fail("serve", f"{flag} must be >= {lo}, got {value}")
    keys = ServerKeys.load(args.keys) if args.keys is not None else None
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s", datefmt="%H:%M:%S")
    if args.insecure and keys is None and not is_loopback(args.bind):
        print(f"racf serve: warning: {args.bind} is served without keys (--insecure): anyone on the network may "
              f"ask, and anyone between a car and this service may read and change its answers", file=sys.stderr,
              flush=True)

    def ready(endpoint: str) -> None:
        link = f"CurveZMQ, cars admitted from {keys.admitted}" if keys else "plain link, no authentication"
        served = (", ".join(f"{n}{' ' + str(o) if o else ''}" for n, o in offers.items()) if offers
                  else "every registered one, with its defaults")
        print(f"listening at {endpoint} (defences: {served}; {link}); Ctrl-C stops", flush=True)

    sessions = Sessions(args.idle_s, args.sessions_per_client, args.max_sessions, args.sessions_per_range)
    served = serve(args.bind, offers, ready=ready, keys=keys, sessions=sessions)
    print(f"answered {served} requests")
    return 0


def _keys(args: argparse.Namespace) -> int:
    from racf.experiments.link.curve import DEFAULT_CAR, make_keys

    cars = tuple(args.car or (DEFAULT_CAR,))
    bad = [c for c in cars if not c.replace("-", "").replace("_", "").isalnum()]
    if bad:
        fail("serve keys", f"car name {bad[0]!r}: letters, digits, - and _ only")
    for path in make_keys(args.dir, cars):
        print(path)
    print(f"serve with `racf serve --keys {args.dir}`; give each car `--service-keys {args.dir}` (it reads "
          f"server.key and cars/NAME.key_secret: --service-car NAME where the folder holds several)")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from racf.experiments.episode import TrialSpec
    import tempfile
    from pathlib import Path

    from racf.experiments.link.curve import CarKeys, make_keys
    from racf.experiments.service.bench import measure, record_samples
    from racf.experiments.sweeps.service_process import service_process
    from racf.plugins import ESTIMATORS

    if args.defence not in ESTIMATORS:
        fail("bench service", f"unknown defence {args.defence!r}; registered: {', '.join(ESTIMATORS)}")
    if args.n < 1:
        fail("bench service", "-n must be >= 1")
    options = estimator_options("bench service", args.estimator_option, (args.defence,),
                                args.defence).get(args.defence, {})
    setting = args.setting or ("attack" if args.defence == "raw" else f"attack+{args.defence}")
    try:
        spec = TrialSpec(setting, args.sign, 1.0, 0, estimator_options=options)
    except ValueError as err:
        fail("bench service", str(err))
    if args.curve and args.endpoint is not None:
        fail("bench service", "--curve starts its own service with fresh keys: drop --endpoint")
    calls, calibration = record_samples(spec)
    if args.endpoint is not None:
        result = measure(args.endpoint, spec.estimator, calls, calibration, args.n, options)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            keys = None
            if args.curve:
                keys = Path(tmp) / "keys"
                make_keys(keys)
            with service_process(spec.estimator, options, keys=keys) as (endpoint, _):
                result = measure(endpoint, spec.estimator, calls, calibration, args.n, options,
                                 keys=CarKeys.load(keys) if keys else None)
    result["episode"] = spec.trial_id
    result["link"] = "curve" if args.curve else "plain"
    if args.json:
        print(json.dumps(result, indent=2, allow_nan=False))
        return 0
    rt, local = result["round_trip"], result["in_process"]
    print(f"racf serve ({result['defence']}) at {result['endpoint']}, {result['link']} link: {rt['n']} steps of "
          f"episode {spec.trial_id}")
    print(f"{'':<22}{'p50':>8}{'p90':>8}{'p99':>8}{'p99.9':>8}{'max':>8}   ms")
    for name, row in (("round trip (service)", rt), ("in-process estimate", local)):
        print(f"{name:<22}{row['p50_ms']:>8.3f}{row['p90_ms']:>8.3f}{row['p99_ms']:>8.3f}{row['p999_ms']:>8.3f}"
              f"{row['max_ms']:>8.3f}")
    print(f"the paper's offboard cycle (perception, transmission, ODCA, control): {result['paper_cycle_ms']:.0f} ms; "
          f"distances differing from in-process: {result['distance_mismatches']}")
    return 0
