"""The command line answers at once: ``racf --version``, ``racf --help`` and a command's ``--help``
import only what that command declares (never torch or scikit-learn, which take seconds), and the
index they read instead of the modules is the modules' own."""

import subprocess
import sys

import pytest

from racf.experiments.cli.commands import COMMANDS, index

#: What takes longest to import: none of it may load for a command's help.
HEAVY = {"torch", "sklearn", "transformers", "chronos", "onnxruntime"}
#: What no command without episodes may load for its help either.
SIMULATOR = {"pandas", "mujoco", "scipy", "cv2", "networkx", "gymnasium"}


def _imported(argv: list[str]) -> set[str]:
    code = ("import sys\nfrom racf.experiments.cli import main\ntry:\n    main(sys.argv[1:])\nexcept SystemExit:\n"
            "    pass\nprint(' '.join(sorted({m.split('.')[0] for m in sys.modules})), file=sys.stderr)")
    done = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=120)
    return set(done.stderr.strip().splitlines()[-1].split())


def test_the_index_is_what_the_modules_declare():
    assert COMMANDS == index(), "stale: `python -m racf.experiments.cli.commands` prints the table anew"


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["bench", "--help"], ["board", "verify", "--help"],
                                  ["odca", "train", "--help"], ["bench", "sim", "--help"], ["scorecard", "--help"]])
def test_the_version_the_list_of_commands_and_light_commands_import_no_simulator(argv):
    assert not _imported(argv) & (HEAVY | SIMULATOR)


@pytest.mark.parametrize("argv", [["trial", "--help"], ["sweep", "--help"], ["bag", "replay", "--help"]])
def test_an_episode_command_s_help_imports_neither_torch_nor_scikit_learn(argv):
    assert not _imported(argv) & HEAVY


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
