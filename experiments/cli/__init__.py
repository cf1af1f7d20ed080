"""The ``racf`` command line: one module per command group, each registering its subcommands
and their handlers. Parsing and printing only; the work lives in the packages beside this one.

What goes wrong reaches the user through one path, :func:`main` (``racf.errors``): a user's
mistake is one line and exit 2, episodes whose code raised are one line and exit 1 (the
tracebacks in a log), an interrupt is one line and exit 130. Only a bug of racf's own shows a
traceback."""

from __future__ import annotations

import argparse
import os
import signal
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from racf.errors import EpisodeFailed, Interrupted, UserError
from racf.experiments.cli.commands import COMMANDS, MODULES
from racf.experiments.cli.common import Parser, fail, load_plugins_from_argv
from racf.experiments.cli.groups import GROUPS, add_groups, canonical_argv

__all__ = ["main", "build_parser"]

#: Exit codes: a user's mistake, episodes that failed, an interrupt (128 + SIGINT, as shells use).
EXIT_USAGE, EXIT_FAILED, EXIT_INTERRUPTED = 2, 1, 130


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The command line's parser. With ``argv``, only the module of the command it runs is imported
    and declares its commands in full; every other command is its name and help from the index
    (``commands.COMMANDS``), enough for ``racf --help`` and for argparse to name the choices."""
    from importlib import import_module

    import racf

    p = Parser(prog="racf", description="RACF testbed: QCar 2 simulation, attacks and ODCA.")
    p.add_argument("--version", action="version", version=f"racf {racf.__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=Parser)
    wanted = set(MODULES) if argv is None else _module_of(argv)
    for name in MODULES:
        if name in wanted:
            import_module(f"racf.experiments.cli.{name}").register(sub)
        else:
            for flat, (module, text) in COMMANDS.items():
                if module == name:
                    sub.add_parser(flat, help=text)  # never parsed: its module declares its flags when it runs
    add_groups(sub)
    return p


def _parse(argv: list[str]):
    """The command line parsed; where a flag is left over, parsed again with the scenarios' older flag
    names declared (``episode_flags.ALIASES``: they load every scenario, which nothing else here needs)."""
    from racf.experiments.cli.episode_flags import ALIASES

    ALIASES["declared"] = False
    args, extra = build_parser(argv).parse_known_args(argv)
    if any(e.startswith("--") for e in extra):
        ALIASES["declared"] = True
        args, extra = build_parser(argv).parse_known_args(argv)
    return args, extra


def _module_of(argv: list[str]) -> set[str]:
    """The module that declares the command ``argv`` runs (none for ``racf --help``, a group's help or
    a name that is no command: their lines need only the index)."""
    words = [a for a in argv if not a.startswith("-")][:2]
    if not words:
        return set()
    flat = GROUPS[words[0]][1].get(words[1] if len(words) > 1 else "") if words[0] in GROUPS else words[0]
    return {COMMANDS[flat][0]} if flat in COMMANDS else set()


def main(argv: list[str] | None = None) -> int:
    """Runs one command; returns its exit code (0 done, 1 episodes failed, 2 bad input, 130 interrupted)."""
    argv = canonical_argv(sys.argv[1:] if argv is None else list(argv))
    command = next((a for a in argv if not a.startswith("-")), "")
    args = None
    try:
        with _sigterm_as_interrupt():
            load_plugins_from_argv(argv)  # plug-ins first: the parser's choices and help list them
            try:
                args, extra = _parse(argv)
            except SystemExit as done:  # --help, --version, or argparse's one line for a bad flag
                return int(done.code or 0)
            if extra:
                fail(_name(args), f"unrecognized arguments: {' '.join(extra)} (`racf {_name(args)} --help` "
                                  f"lists what is allowed)")
            if getattr(args, "address", None) is not None and args.backend != "ray":
                fail(args.command, "--address joins a Ray cluster: it needs --backend ray")
            return args.handler(args)
    except BrokenPipeError:  # the reader stopped reading (`racf ... | head`): what it took is all it wanted
        _quiet_stdout()
        return 0
    except (UserError, OSError) as err:  # a path, value, spec, plug-in, checkpoint or dataset that cannot be used
        _say(args, command, _words(err))
        return EXIT_USAGE
    except EpisodeFailed as err:
        _say(args, command, str(err))
        return EXIT_FAILED
    except Interrupted as err:
        _say(args, command, str(err))
        return EXIT_INTERRUPTED
    except KeyboardInterrupt:
        _say(args, command, "interrupted; nothing half-written was kept")
        return EXIT_INTERRUPTED
    except Exception as err:
        from racf.experiments.sweeps.failures import plugin_fault

        fault = plugin_fault(err)
        if fault is None:
            raise  # a bug of racf's own: its traceback is what a report needs
        log = _write_log(args, fault)
        _say(args, command, f"{fault.where} raised {fault.error}; traceback in {log}")
        return EXIT_FAILED


def _quiet_stdout() -> None:
    """Points stdout at /dev/null, so that Python's flush at exit does not meet the closed pipe again
    (the recipe of Python's `signal` documentation)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # not a file (a test's capture): nothing to flush to a pipe
        return
    os.dup2(os.open(os.devnull, os.O_WRONLY), fd)


def _say(args, guess: str, message: str) -> None:
    """``racf COMMAND: MESSAGE`` on one line (the command as parsed, else the first word given)."""
    command = _name(args) or guess
    prefix = f"racf {command}:" if command else "racf:"
    message = " ".join(str(message).split())  # one line, whatever the message held
    print(message if message.startswith("racf ") else f"{prefix} {message}", file=sys.stderr)


def _name(args) -> str | None:
    """The command as parsed: ``trials``, or a group's ``bench sim``."""
    command = getattr(args, "command", None)
    sub = getattr(args, "subcommand", None)
    return f"{command} {sub}" if command and sub else command


def _words(err: BaseException) -> str:
    if isinstance(err, OSError):
        where = f": {err.filename}" if err.filename else ""
        return f"{err.strerror or err}{where}"
    return str(err)


def _write_log(args, fault) -> Path:
    from racf.experiments.sweeps.failures import append_log

    out = getattr(args, "out", None) if args is not None else None
    folder = Path(out) if out is not None else Path("outputs")
    return append_log(folder, fault, first=True)


@contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM stops a command as Ctrl-C does: what is stored stays, and the line says how to resume."""
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    try:
        old = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread (a test's runner): leave SIGTERM as it is
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)
