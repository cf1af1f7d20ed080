"""The flags that name episodes (``racf trial``, ``racf trials``, ``racf bag export``): what runs, its
scenario (with the older names some scenarios' parameters keep: ``--traffic-cars``), and how; and the
spec they make."""

from __future__ import annotations

import argparse

from racf.experiments.cli.common import (_detector_names, attack_help, duration, estimator_help, estimator_option_flag,
                                         estimator_options, fail, flag_error, keyed_values, pair, plain_values,
                                         plugin_flag, sensor_flags, service_flags, service_params, share, sign, speed)

__all__ = ["episode_flags", "episode_params", "trial_flags", "trial_spec", "scenario_alias_flags", "aliased_scenario"]


def episode_flags(p: argparse.ArgumentParser) -> None:
    """The flags ``racf trial`` and ``racf trials`` share: what runs and how."""
    p.add_argument("--setting", default=None,
                   help="clean or attack, then extra attacks and an estimator joined by '+', e.g. attack+odca, "
                        "attack+lidar_spoof+odca (default clean; --attack/--estimator compose one instead)")
    p.add_argument("--attack", default=None, metavar="A[,B]",
                   help=f"attacks, comma-separated: {attack_help()} (default none)")
    p.add_argument("--estimator", default=None,
                   help=f"distance estimator: {estimator_help()} (default raw)")
    p.add_argument("--rho", type=share, nargs="+", default=None, metavar="R",
                   help="patch coverage, a value or LOW HIGH (uniform), in [0, 1] (default 0.9 1.0)")
    p.add_argument("--t-atk", type=duration, nargs="+", default=None, metavar="S",
                   help="attack duration s, a value or LOW HIGH (uniform) (default 0.5 3.0)")
    p.add_argument("--delay-ms", type=float, default=0.0,
                   help="perception-to-actuation delay, ms (default 0; the paper's offboard loop: 49)")
    p.add_argument("--control-hz", type=float, default=None, help="controller rate, Hz (default: every 50 Hz step)")
    p.add_argument("--detector", choices=_detector_names(), default=None,
                   help="the car's stop-sign detector: classical (colour and shape; default) or learned (the "
                        "segmenter; the default of --table --patch physical)")
    p.add_argument("--stable-steps", type=int, default=None,
                   help="steps the sign must be visible before an attack may start (default: the braking "
                        "controller's confirm_frames + 3 = 6)")
    scenario_alias_flags(p)
    p.add_argument("--scenario-param", action="append", default=[], metavar="KEY=VALUE",
                   help="a parameter of the scenario (--target; `racf list scenarios` lists each one's, with "
                        "ranges); repeatable, values are TOML, e.g. leave_s=2.5")
    p.add_argument("--metric", action="append", default=[], metavar="NAME",
                   help="also score this metric (repeatable; `racf list` lists them: those not scored on every "
                        "episode are marked 'asked')")
    p.add_argument("--attack-param", action="append", default=[], metavar="ATTACK.KEY=VALUE",
                   help="a setting of one of the attacks (repeatable; values are TOML), e.g. "
                        "depth_bias.bias_m=1.5, or its schedule: depth_bias.trigger=at_time depth_bias.start_s=2.0 "
                        "starts it 2 s into the episode (the attack page lists each attack's settings and ranges)")
    p.add_argument("--supervisor", action="store_true",
                   help="run the supervisor (runtime assurance with a stated guarantee: docs/concepts/guarantee.md) "
                        "over the defence, where the scenario follows a car (lead_vehicle)")
    estimator_option_flag(p)
    service_flags(p)
    plugin_flag(p)
    sensor_flags(p)


#: Whether the parser declares the scenarios' older flag names. Declaring them loads every scenario
#: (a second): the command line asks for them only when a flag is left unparsed without them
#: (``racf.experiments.cli.main``), so that ``--help`` and every other command line stay quick.
ALIASES = {"declared": False}


def scenario_alias_flags(p: argparse.ArgumentParser) -> None:
    """A flag for every scenario parameter an older name stands for (``Scenario.aliases``):
    ``--traffic-cars N`` is ``--target cross_traffic --scenario-param cars=N``; declared only where
    ``ALIASES`` says (see there)."""
    if not ALIASES["declared"]:
        return
    from racf.plugins import SCENARIOS

    for name in SCENARIOS:
        scenario = SCENARIOS[name]
        for alias, param_name in scenario.aliases.items():
            param = scenario.param(param_name)
            p.add_argument(f"--{alias.replace('_', '-')}", dest=alias, type=param.type, default=None,
                           metavar=param.unit.upper() or "VALUE",
                           help=f"scenario {name}'s {param_name}: {param.meaning} ({param.allowed()}); sets --target "
                                f"{name}")


def aliased_scenario(args: argparse.Namespace, command: str, target: str, situation: dict) -> tuple[str, dict]:
    """The scenario and its parameters once the alias flags (:func:`scenario_alias_flags`) are read:
    any of a scenario's alias flags runs that scenario (a sign approach's variant: ``--target sign``
    or the scenario itself), with the flags' values under ``--scenario-param``'s."""
    if not ALIASES["declared"]:  # no older name was on the command line
        return target, situation
    from racf.plugins import SCENARIOS

    for name in SCENARIOS:
        scenario = SCENARIOS[name]
        given = {param: getattr(args, alias) for alias, param in scenario.aliases.items()
                 if getattr(args, alias, None) is not None}
        if not given:
            continue
        flags = ", ".join(f"--{a.replace('_', '-')}" for a, param in scenario.aliases.items() if param in given)
        if target not in (name, scenario.target):
            flag_error(command, f"{flags} set scenario {name!r} (a {scenario.target} approach); --target {target} "
                                "cannot take it")
        target, situation = name, given | situation
    return target, situation


def trial_flags(p: argparse.ArgumentParser) -> None:
    """The flags that name one episode (``racf trial``, ``racf bag export``): the episode flags and
    its target, speed and seed."""
    from racf.plugins import SCENARIOS

    episode_flags(p)
    p.add_argument("--sign", type=sign, default=None,
                   help="stop sign 0-3, or crate 0-1 with --target obstacle (default 2, or 0 where the scenario "
                        "has fewer: a drive, a crate)")
    p.add_argument("--target", choices=SCENARIOS.names(), default="sign", metavar="SCENARIO",
                   help=f"the scenario: {', '.join(SCENARIOS.names())} (default sign: approach a stop sign; obstacle: a "
                        "crate; drive: a random 20-60 s drive, --sign 0; `racf list scenarios` says what each is; "
                        "older flag names a scenario declares for its parameters still work)")
    p.add_argument("--speed", type=speed, default=1.0, help="cruise speed m/s, 0.1-3.0 (default 1.0)")
    p.add_argument("--seed", type=int, default=0)


#: The stop sign an episode approaches unless told: sign 2, as the paper's figures.
DEFAULT_SIGN = 2


def default_index(target: str) -> int:
    """The target an episode of scenario ``target`` goes to unless told: sign 2, or 0 where the
    scenario has no third (a drive has one, the obstacle two crates)."""
    from racf.experiments.episode.spec import TARGETS
    from racf.plugins import SCENARIOS

    return DEFAULT_SIGN if TARGETS[SCENARIOS[target].target] > DEFAULT_SIGN else 0


def trial_spec(args: argparse.Namespace, command: str):
    """The one episode :func:`trial_flags` name, as a ``TrialSpec``; exits 2 naming what is wrong."""
    from racf.experiments.episode import TrialSpec, parse_setting

    setting, params = episode_params(args, command)
    params["estimator_options"] = params["estimator_options"].get(parse_setting(setting)[1], {})
    try:
        index = args.sign if args.sign is not None else default_index(params.get("target", "sign"))
        return TrialSpec(setting, index, args.speed, args.seed, **params)
    except ValueError as err:
        fail(command, str(err))


def episode_params(args: argparse.Namespace, command: str, table: bool = False) -> tuple[str | None, dict]:
    """The setting and the spec fields the episode flags give; UsageError naming what is wrong.
    With ``table`` the settings are the table's own: none may be given, and the setting is None.
    ``estimator_options`` is by estimator name ({"odca": {"checkpoint": ...}}): a batch gives each
    setting its own estimator's."""
    from racf.experiments.episode import STRONG_RHO, STRONG_T_ATK_S, parse_setting, setting_name

    try:
        if table and (args.setting is not None or args.attack is not None or args.estimator is not None):
            flag_error(command, "--table runs its own settings; drop --setting/--attack/--estimator")
        if args.setting is not None and (args.attack is not None or args.estimator is not None):
            flag_error(command, "give --setting, or --attack/--estimator, not both")
        if table:
            setting = None
        elif args.setting is not None:
            setting = args.setting
            parse_setting(setting)
        else:
            attacks = [a.strip() for a in args.attack.split(",") if a.strip()] if args.attack else []
            setting = setting_name(attacks, args.estimator or "raw")
        if setting is not None and not parse_setting(setting)[0] and (args.rho is not None or args.t_atk is not None):
            flag_error(command, "--rho and --t-atk apply to settings with an attack")
        if table:
            from racf.experiments.episode import TABLE_SETTINGS

            used = tuple(dict.fromkeys(parse_setting(s)[1] for s in TABLE_SETTINGS))
            options = estimator_options(command, args.estimator_option, used)
        else:
            options = estimator_options(command, args.estimator_option, (parse_setting(setting)[1],),
                                        default=parse_setting(setting)[1])
        attack_params = keyed_values(command, "--attack-param", args.attack_param)
        if attack_params and (table or not set(attack_params) <= set(parse_setting(setting)[0])):
            flag_error(command, f"--attack-param names attack(s) {sorted(attack_params)}; this command runs "
                                f"{'its table' if table else list(parse_setting(setting)[0]) or 'no attack'}")
        params = {"rho": pair(command, "--rho", args.rho, STRONG_RHO), "attack_params": attack_params,
                  "t_atk": pair(command, "--t-atk", args.t_atk, STRONG_T_ATK_S),
                  "delay_ms": args.delay_ms, "control_hz": args.control_hz, "stable_steps": args.stable_steps,
                  "sensor_profile": args.sensor_profile, "sign_geometry": args.sign_geometry,
                  "detector": args.detector or "classical", "estimator_options": options,
                  "supervisor": bool(getattr(args, "supervisor", False))}
        target = getattr(args, "target", "sign")
        situation = plain_values(command, "--scenario-param", args.scenario_param)
        target, situation = aliased_scenario(args, command, target, situation)
        params |= {"target": target, "scenario_params": situation, "metrics": tuple(args.metric),
                   **service_params(args, command)}
    except ValueError as err:
        flag_error(command, str(err))
    return setting, params
