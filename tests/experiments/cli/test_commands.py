"""The command line answers at once: ``racf --version``, ``racf --help`` and a command's ``--help``
import only what that command declares (never torch or scikit-learn, which take seconds), and the
index they read instead of the modules is the modules' own."""

import subprocess
import sys

from racf.experiments.cli.commands import COMMANDS, index

#: What takes longest to import: none of it may load for a command's help.
HEAVY = {"torch", "sklearn", "transformers", "chronos", "onnxruntime"}
#: What no command without episodes may load for its help either.
SIMULATOR = {"pandas", "mujoco", "scipy", "cv2", "networkx", "gymnasium"}


def test_the_index_is_what_the_modules_declare():
    assert COMMANDS == index(), "stale: `python -m racf.experiments.cli.commands` prints the table anew"


_EVERY_HELP = """
import contextlib, io, sys
from racf.experiments.cli import main
from racf.experiments.cli.commands import COMMANDS
from racf.experiments.cli.groups import GROUPS
grouped = {flat: [g, short] for g, (_, commands) in GROUPS.items() for short, flat in commands.items()}
heavy = set(sys.argv[1:])
for argv in [["--version"], ["--help"], *[[g, "--help"] for g in GROUPS],
             *[[*grouped.get(flat, [flat]), "--help"] for flat in COMMANDS]]:
    with contextlib.redirect_stdout(io.StringIO()):
        main(argv)
    loaded = sorted(heavy & {m.split(".")[0] for m in sys.modules})
    if loaded:
        print(" ".join(argv), "imported", loaded)
        break
"""


def test_every_help_and_the_version_import_neither_torch_nor_the_simulator():
    """Every command's --help (each group's and the top level's too), one after the other in one process:
    none of them imports what takes seconds, so each answers at once (about 0.1 s on 2 cores)."""
    done = subprocess.run([sys.executable, "-c", _EVERY_HELP, *sorted(HEAVY | SIMULATOR)], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0 and done.stdout == "", done.stdout + done.stderr[-2000:]


def test_the_flags_choices_name_what_the_simulator_defines():
    from racf.experiments.cli.common import SENSOR_PROFILE_NAMES, SIGN_GEOMETRY_NAMES
    from racf.sim.env.config import SENSOR_PROFILES
    from racf.sim.world.stop_signs import SIGN_GEOMETRIES

    assert SENSOR_PROFILE_NAMES == tuple(SENSOR_PROFILES) and SIGN_GEOMETRY_NAMES == tuple(SIGN_GEOMETRIES)


def test_the_battery_names_the_help_offers_are_the_batteries():
    from racf.experiments.scorecard.battery import BATTERIES
    from racf.experiments.scorecard.battery_names import BATTERY_NAMES, DEFAULT_BATTERY

    assert BATTERY_NAMES == tuple(BATTERIES) and DEFAULT_BATTERY in BATTERIES


def test_a_registry_names_its_parts_as_it_lists_them():
    from racf.plugins import REGISTRIES

    for registry in REGISTRIES.values():
        assert registry.names() == tuple(registry)
