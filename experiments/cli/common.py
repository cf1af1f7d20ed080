"""What the command groups share: argument types, the episode and backend flags, and formatting."""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import NoReturn

from racf.errors import UserError

__all__ = ["UsageError", "Parser", "output_dir", "unwritable", "sign", "positive", "speed", "share",
           "duration", "count", "pair", "fail", "flag_error", "fmt_ci", "DEFAULT_WORKERS", "backend_flags", "sensor_flags", "attack_help", "estimator_help", "keyed_values",
           "registry_rows", "registry_markdown", "plugin_flag", "estimator_option_flag", "estimator_options",
           "load_plugins_from_argv"]

#: Parallel episodes by default: two, or one on a single-core machine.
DEFAULT_WORKERS = min(2, os.cpu_count() or 1)


def sign(value: str) -> int:
    try:
        index = int(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"sign must be an integer 0..3, got {value!r}") from None
    if index not in range(4):
        raise argparse.ArgumentTypeError(f"sign must be 0, 1, 2 or 3, got {index}")
    return index


def positive(value: str) -> float:
    v = float(value)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {value}")
    return v


def _within(name: str, low: float, high: float, unit: str = ""):
    """An argparse type: a float in [low, high]; the error names the flag's quantity and range."""
    def parse(value: str) -> float:
        v = float(value)
        if not low <= v <= high:
            raise argparse.ArgumentTypeError(f"{name} must be in [{low:g}, {high:g}]{unit}, got {value}")
        return v
    return parse


speed = _within("speed", 0.1, 3.0, " m/s")
share = _within("rho", 0.0, 1.0)
duration = _within("t-atk", 0.0, 60.0, " s")


def at_least(minimum: int):
    """A flag's type: a whole number of at least ``minimum`` (argparse's one line names a bad one)."""
    def whole(value: str) -> int:
        try:
            n = int(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {minimum}, got {value!r}") from None
        if n < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {n}")
        return n
    return whole


#: A count of things: a whole number >= 1.
count = at_least(1)


def pair(command: str, name: str, values: list[float] | None, default: tuple[float, float]) -> tuple[float, float]:
    """A value or LOW HIGH as (low, high); a bad one exits 2 like any bad flag."""
    if values is None:
        return default
    if len(values) > 2 or (len(values) == 2 and values[0] > values[1]):
        flag_error(command, f"{name} takes a value or LOW HIGH with LOW <= HIGH, got {values}")
    return (values[0], values[-1])


class UsageError(UserError):
    """Bad input a handler found before any work: ``main`` prints it and returns 2."""


class Parser(argparse.ArgumentParser):
    """racf's parsers: an option is taken only by its whole name. argparse's default accepts any
    unique prefix, so ``racf trials --sign 3`` (trials has no ``--sign``) became
    ``--sign-geometry 3`` and was refused with a message about sign geometry."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        """One line, not argparse's usage wall: what is wrong, and where the options are listed."""
        self.exit(2, f"{self.prog}: {message} (`{self.prog} --help` lists what is allowed)\n")


def unwritable(path: Path) -> str | None:
    """Why results cannot be written into folder ``path`` (made later if missing), or None.

    The nearest folder that exists must be a folder racf can create files in: a path under a
    regular file, under ``/proc``, or in a folder the user may not write is refused before any
    work, not after the first episode."""
    path = Path(path).expanduser()
    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"{path} cannot be a results folder: {existing} is a file, not a folder"
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as err:
        return f"{path} cannot be a results folder: {existing} is not writable ({err.strerror or err})"
    return None


def output_dir(value: str) -> Path:
    """An argparse type: a results folder racf can write (see :func:`unwritable`)."""
    problem = unwritable(Path(value))
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return Path(value).expanduser()


def fail(command: str, message: str) -> NoReturn:
    """Stops the command: ``racf COMMAND: MESSAGE`` on stderr, and exit code 2. A message that already
    holds the prefix (a UsageError caught and raised again as another's message) keeps it once."""
    prefix = f"racf {command}: "
    raise UsageError(prefix + str(message).removeprefix(prefix))


def flag_error(command: str, message: str) -> NoReturn:
    """A bad flag the handler found (the episode flags are checked together): as :func:`fail`."""
    fail(command, message)


def fmt_ci(lo: float, hi: float, digits: int = 2) -> str:
    return f"[{lo:.{digits}f}, {hi:.{digits}f}]"


def attack_help() -> str:
    """The registered attacks, for a flag's help (their names: nothing is imported)."""
    from racf.plugins import ATTACKS

    return ", ".join(ATTACKS.names())


def estimator_help() -> str:
    """The registered estimators, for a flag's help (their names: nothing is imported)."""
    from racf.plugins import ESTIMATORS

    return ", ".join(ESTIMATORS.names())


def plugin_flag(p: argparse.ArgumentParser) -> None:
    """``--plugin FILE``: a user's estimator, attack or detector from a Python file (read before
    the parser is built, by :func:`load_plugins_from_argv`, so the choices include it)."""
    p.add_argument("--plugin", action="append", default=[], metavar="FILE.py",
                   help="load an estimator, attack, detector or scenario from a Python file (repeatable); it is then valid "
                        "wherever a built-in one is, and its source enters the result ids")


def load_plugins_from_argv(argv: list[str]) -> None:
    """Loads every ``--plugin FILE`` of a command line (PluginError names a bad one)."""
    from racf.plugins import PluginError, load_plugin_file

    for i, token in enumerate(argv):
        if token == "--plugin":
            if i + 1 >= len(argv):
                raise PluginError("--plugin needs a file: --plugin path/to/file.py")
            load_plugin_file(argv[i + 1])
        elif token.startswith("--plugin="):
            load_plugin_file(token.split("=", 1)[1])


def estimator_option_flag(p: argparse.ArgumentParser) -> None:
    """``--estimator-option [NAME.]KEY=VALUE``: an option of the estimator (e.g. ``checkpoint=outputs/odca-head``)."""
    p.add_argument("--estimator-option", action="append", default=[], metavar="[NAME.]KEY=VALUE",
                   help="an option of the estimator, e.g. checkpoint=outputs/odca-head, or odca.checkpoint=... to name "
                        "the estimator (repeatable; values are TOML: numbers, true/false, else text); options and "
                        "the content of a file they name enter the result ids")


def estimator_options(command: str, values: list[str], estimators: tuple[str, ...],
                      default: str | None = None) -> dict[str, dict]:
    """``--estimator-option`` values as {estimator: {key: value}}; a bare KEY applies to ``default``
    (the one estimator a command runs). Exits 2 naming a bad one."""
    import tomllib

    from racf.experiments.car.estimators import check_options, make_estimator

    out: dict[str, dict] = {}
    for item in values:
        key, sep, raw = item.partition("=")
        if not sep or not key.strip():
            flag_error(command, f"--estimator-option takes [NAME.]KEY=VALUE, got {item!r}")
        name, dot, key = key.strip().rpartition(".")
        if not dot:
            if default is None:
                flag_error(command, f"--estimator-option {item!r}: name the estimator (NAME.KEY=VALUE, one of "
                                    f"{list(estimators)})")
            name = default
        if name not in estimators:
            flag_error(command, f"--estimator-option {item!r}: this command runs estimator(s) {list(estimators)}, "
                                f"not {name!r}")
        try:
            value = tomllib.loads(f"v = {raw}")["v"]
        except tomllib.TOMLDecodeError:
            value = raw
        out.setdefault(name, {})[key] = value
    for name, options in out.items():
        try:
            check_options(name, options)
            make_estimator(name, options)  # a checkpoint that is missing or corrupt fails here, before any work
        except ValueError as err:
            flag_error(command, f"--estimator-option: {err}")
    return out


def keyed_values(command: str, flag: str, values: list[str]) -> dict[str, dict]:
    """``NAME.KEY=VALUE`` items as {NAME: {KEY: value}}, values read as TOML (else text)."""
    import tomllib

    out: dict[str, dict] = {}
    for item in values:
        key, sep, raw = item.partition("=")
        name, dot, key = key.strip().partition(".")
        if not (sep and dot and name and key):
            flag_error(command, f"{flag} takes NAME.KEY=VALUE, got {item!r}")
        try:
            value = tomllib.loads(f"v = {raw}")["v"]
        except tomllib.TOMLDecodeError:
            value = raw
        out.setdefault(name, {})[key] = value
    return out


def plain_values(command: str, flag: str, values: list[str]) -> dict:
    """``KEY=VALUE`` items as {KEY: value}, values read as TOML (else text)."""
    import tomllib

    out: dict = {}
    for item in values:
        key, sep, raw = item.partition("=")
        if not (sep and key.strip().isidentifier()):
            flag_error(command, f"{flag} takes KEY=VALUE, got {item!r}")
        try:
            out[key.strip()] = tomllib.loads(f"v = {raw}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = raw
    return out


def registry_rows(registry: dict) -> list[tuple[str, str]]:
    """(name, one-line description) of each registered class, from its docstring's first sentence."""
    rows = []
    for name, cls in registry.items():
        doc = " ".join((getattr(cls, "description", None) or getattr(cls, "meaning", None) or cls.__doc__
                        or "").strip().split("\n\n")[0].split())
        first = doc.replace("``", "`").split(". ")[0].split(" (:mod:")[0].rstrip(".")
        rows.append((name, first))
    return rows


def registry_markdown() -> str:
    """The tables of attacks, estimators, detectors, scenarios, metrics and car stages, made from the registries."""
    from racf.plugins import ATTACKS, CAR_STAGES, DETECTORS, ESTIMATORS, METRICS, SCENARIOS

    lines = []
    for title, registry in (("attack", ATTACKS), ("estimator", ESTIMATORS), ("detector", DETECTORS),
                            ("scenario", SCENARIOS), ("metric", METRICS), ("car stage", CAR_STAGES)):
        lines += [f"| {title} | what it does |", "|---|---|"]
        lines += [f"| `{name}` | {text} |" for name, text in registry_rows(registry)]
        lines.append("")
    return "\n".join(lines)


def backend_flags(p: argparse.ArgumentParser, workers_help: str = "parallel processes") -> None:
    """``--backend``, ``--address`` and ``--workers``: where a command's episodes run."""
    from racf.experiments.sweeps.executors import BACKENDS

    p.add_argument("--backend", choices=BACKENDS, default="local",
                   help="local spawned processes (default) or Ray")
    p.add_argument("--address", default=None,
                   help="with --backend ray: the cluster to join (default: start a local Ray of its own)")
    p.add_argument("--workers", type=count, default=DEFAULT_WORKERS, help=workers_help)


#: The sensor profiles and sign builds by name, for the flags' choices: the simulator that defines
#: them (``sim.env.config.SENSOR_PROFILES``, ``sim.world.stop_signs.SIGN_GEOMETRIES``) takes a second
#: to import, and ``--help`` must not wait for it (a test holds the names equal).
SENSOR_PROFILE_NAMES = ("qcar2", "ideal")
SIGN_GEOMETRY_NAMES = ("plate", "pole")


def sensor_flags(p, default: str | None = "qcar2", geometry_default: str | None = "plate") -> None:
    """``--sensor-profile`` (the car's sensors) and ``--sign-geometry`` (the stop signs' build)."""
    p.add_argument("--sensor-profile", choices=SENSOR_PROFILE_NAMES, default=default,
                   help="the car's sensors: qcar2, as the QCar 2 delivers them (the A2M12 swept over its "
                        "revolution through Quanser's driver, the camera at 30 Hz, the car's own localisation; "
                        "default), or ideal (a one-instant 360-beam LiDAR, 50 Hz camera, the true pose: an ablation)")
    p.add_argument("--sign-geometry", choices=SIGN_GEOMETRY_NAMES, default=geometry_default,
                   help="the stop signs' build: plate, the LiDAR's scan plane meets the plate (default), or pole, "
                        "it meets only the 6 mm pole")


def _detector_names() -> tuple[str, ...]:
    from racf.plugins import DETECTORS

    return DETECTORS.names()


def service_flags(p: argparse.ArgumentParser) -> None:
    """``--estimator-endpoint`` (run the defence in a ``racf serve`` process) and its timeout."""
    p.add_argument("--estimator-endpoint", default=None, metavar="tcp://HOST:PORT",
                   help="run the defence in the `racf serve` process listening there: its measured round trip "
                        "delays the car, and a step it does not answer in time falls back to the car's onboard "
                        "defence (--estimator-fallback; logged); default: in the car's own process")
    p.add_argument("--estimator-fallback", default=None, metavar="NAME",
                   help="with --estimator-endpoint: the onboard defence the car runs beside the served one and "
                        "drives on where the service gives no answer: an estimator's name, or raw (its own depth, "
                        "unrepaired); default: odca, from its ONNX export")
    from racf.experiments.link.timing import DEFAULT_TIMEOUT_MS

    p.add_argument("--estimator-timeout-ms", type=float, default=None, metavar="MS",
                   help=f"with --estimator-endpoint: how long the car waits for an answer, ms (default "
                        f"{DEFAULT_TIMEOUT_MS:g})")
    p.add_argument("--service-keys", default=None, metavar="DIR",
                   help="with --estimator-endpoint: the key folder of `racf serve keys DIR`; the car pins the "
                        "service's key and shows its own (CurveZMQ); default: a plain link")
    p.add_argument("--service-car", default=None, metavar="NAME",
                   help="with --service-keys: the car whose key the car shows (DIR/cars/NAME.key_secret); "
                        "default: the only car the folder holds")


def service_params(args: argparse.Namespace, command: str) -> dict:
    """The spec fields the service flags give (none without an endpoint)."""
    if args.estimator_endpoint is None:
        for flag, value in (("--estimator-timeout-ms", args.estimator_timeout_ms),
                            ("--estimator-fallback", args.estimator_fallback),
                            ("--service-keys", args.service_keys), ("--service-car", args.service_car)):
            if value is not None:
                flag_error(command, f"{flag} applies with --estimator-endpoint")
        return {}
    if args.service_car is not None and args.service_keys is None:
        flag_error(command, "--service-car names a car of the key folder: give --service-keys DIR too")
    out = {"estimator_endpoint": args.estimator_endpoint, "estimator_keys": args.service_keys,
           "estimator_car": args.service_car}
    if args.estimator_timeout_ms is not None:
        out["estimator_timeout_ms"] = args.estimator_timeout_ms
    if args.estimator_fallback is not None:
        out["estimator_fallback"] = args.estimator_fallback
    return out
