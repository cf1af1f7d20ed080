"""The plug-in registries: entry points, files, run-time registration, and versioned ids."""

from __future__ import annotations

import pytest

from racf.experiments.episode import TrialSpec
from racf.plugins import ATTACKS, DETECTORS, ESTIMATORS, PluginError, load_plugin_file
from racf.sim.attacks import AttackWrapper

ATTACK_FILE = '''
from racf.sim.attacks import AttackSchedule, AttackWrapper


class ZeroDepth(AttackWrapper):
    """Blanks the whole depth image."""

    name = "depth_zero"

    def __init__(self, env, **schedule):
        super().__init__(env, AttackSchedule(**schedule))

    def _attack(self, obs, info):
        obs["depth"] = obs["depth"] * {factor}
        return obs
'''


def test_racf_registers_its_own_parts_through_its_entry_points():
    assert {"raw", "odca", "ekf", "chronos"} <= set(ESTIMATORS)
    assert {"classical", "learned"} <= set(DETECTORS)
    assert all(ATTACKS.plugin(name).builtin and ATTACKS.plugin(name).source is None for name in ATTACKS)
    assert ESTIMATORS.source_id("odca") is None


def test_an_attack_registered_from_a_script_is_valid_in_a_setting(plugin_env, tmp_path):
    path = tmp_path / "zero.py"
    path.write_text(ATTACK_FILE.format(factor=0))
    with pytest.raises(ValueError, match="unknown part"):
        TrialSpec("clean+depth_zero", 0, 1.0, 0)
    (plugin,) = load_plugin_file(path)
    assert plugin.name == "depth_zero" and issubclass(plugin.obj, AttackWrapper)
    spec = TrialSpec("clean+depth_zero+odca", 0, 1.0, 0)
    assert spec.attacks == ("depth_zero",)


def test_editing_a_plugin_changes_the_ids_of_its_results_only(plugin_env, tmp_path):
    path = tmp_path / "zero.py"
    path.write_text(ATTACK_FILE.format(factor=0))
    load_plugin_file(path)
    attacked, clean = TrialSpec("clean+depth_zero", 0, 1.0, 0), TrialSpec("clean", 0, 1.0, 0)
    before = attacked.trial_id, clean.trial_id
    path.write_text(ATTACK_FILE.format(factor=0.5))
    assert attacked.trial_id != before[0] and clean.trial_id == before[1]


def test_a_taken_name_and_a_non_part_are_refused(plugin_env):
    class Impostor(AttackWrapper):
        name = "depth_bias"

    with pytest.raises(PluginError, match="already registered by racf"):
        ATTACKS.register(Impostor)
    with pytest.raises(PluginError, match="is not an estimator"):
        ESTIMATORS.register(int, "integer")
    with pytest.raises(PluginError, match="unknown detector 'yolo'; choose from"):
        DETECTORS.plugin("yolo")


@pytest.mark.parametrize("text, message", [
    (None, "no such file"),
    ("import not_a_module_anywhere\n", "failed to import: ModuleNotFoundError"),
    ("x = 1\n", "defines no estimator, attack, detector, scenario, metric or car stage"),
])
def test_a_bad_plugin_file_is_named(plugin_env, tmp_path, text, message):
    path = tmp_path / "mine.py"
    if text is not None:
        path.write_text(text)
    with pytest.raises(PluginError, match=message):
        load_plugin_file(path)


def test_a_broken_entry_point_is_named_once_and_stops_only_what_needs_it(plugin_env, tmp_path, monkeypatch, capsys):
    """An installed plug-in whose class is gone: reported once on stderr, left out of the registry
    (racf's own parts and every command that does not name it work), named where it is asked for,
    and listed as broken by ``racf list``."""
    from racf.experiments.cli import main

    info = tmp_path / "broken-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: broken\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[racf.estimators]\nbroken = no_such_module:Defence\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delenv("RACF_REPORTED_BROKEN", raising=False)
    assert "odca" in ESTIMATORS and "broken" not in ESTIMATORS and "broken" not in list(ESTIMATORS)
    said = capsys.readouterr().err
    assert said.count("failed to load") == 1 and "'broken' (no_such_module:Defence, from broken)" in said
    with pytest.raises(PluginError, match="'broken' .*from broken.* failed to load: ModuleNotFoundError"):
        ESTIMATORS["broken"]
    with pytest.raises(ValueError, match="failed to load"):
        TrialSpec("clean+broken", 0, 1.0, 0)
    assert "broken" in ESTIMATORS.broken
    assert main(["list"]) == 0
    listed = capsys.readouterr()
    assert "broken plug-ins" in listed.out and "no_such_module:Defence" in listed.out
    assert listed.err.count("failed to load") == 0  # reported once for the process


def test_an_installed_plugin_is_found_and_versioned_by_its_package(cusum_installed):
    plugin = ESTIMATORS.plugin("lidar_cusum")
    assert plugin.origin == "racf-cusum" and not plugin.builtin
    spec = TrialSpec("attack+lidar_cusum", 0, 1.0, 0)
    before = spec.trial_id
    (cusum_installed / "__init__.py").write_text((cusum_installed / "__init__.py").read_text() + "\n# edited\n")
    assert spec.trial_id != before


DETECTOR_FILE = '''
class Blind:
    """Sees nothing, ever."""

    name = "blind"

    def detect(self, rgb):
        return None
'''


def test_a_plugin_detector_is_among_the_clis_choices(plugin_env, tmp_path):
    from racf.experiments.cli import build_parser
    from racf.experiments.cli.common import load_plugins_from_argv

    path = tmp_path / "blind.py"
    path.write_text(DETECTOR_FILE)
    argv = ["trial", "--plugin", str(path), "--detector", "blind"]
    load_plugins_from_argv(argv)
    assert build_parser().parse_args(argv).detector == "blind"
    assert DETECTORS.plugin("blind").origin == str(path)
    assert TrialSpec("clean", 0, 1.0, 0, detector="blind").trial_id != TrialSpec("clean", 0, 1.0, 0).trial_id


def test_a_class_defined_without_a_file_is_versioned_by_its_code(plugin_env):
    namespace: dict = {"__name__": "__notebook__"}
    source = '''
class Halver:
    name = "halver"
    def reset(self): pass
    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0): return sample.d_meas * {k}
    def diagnostics(self): return {{}}
    def would_pass(self, *, depth, speed_mps, dt, yaw_rate_radps=0.0, lidar_shift=0.0): return True
'''
    exec(source.format(k=0.5), namespace)
    ESTIMATORS.register(namespace["Halver"])
    spec = TrialSpec("clean+halver", 0, 1.0, 0)
    before = spec.trial_id
    exec(source.format(k=0.25), namespace)  # edited and defined again, as in a notebook cell
    ESTIMATORS.register(namespace["Halver"])
    assert ESTIMATORS.plugin("halver").origin == "interactive" and spec.trial_id != before
