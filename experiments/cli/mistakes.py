"""The corpus of a user's mistakes and what racf says to each: one line and exit 2, before any
episode runs, never a traceback. The tests run every one (``tests/experiments/cli/test_bad_inputs.py``)
and the CLI reference page lists them, so the page shows what the tests check.

A command holds ``{placeholders}``: ``{tmp}`` is a scratch folder, the others files that
:func:`make_files` writes into it (a corrupt dataset, a broken plug-in, ...)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["MISTAKES", "make_files", "mistakes_markdown"]

#: (command line, words the one line holds)
MISTAKES: list[tuple[str, str]] = [
    # values
    ("trial --speed fast", "speed"),
    ("trial --sign 9", "sign"),
    ("trials -n 0", ">= 1"),
    ("trial --rho 2", "rho"),
    ("trial --estimator kalman", "estimator must be one of"),
    ("trial --attack laser", "unknown attack"),
    ("trial --detector yolo", "invalid choice"),
    ("trial --setting attack --target obstacle --sign 0", "cannot act on target 'obstacle'"),
    ("trial --setting clean+lead_patch+odca", "acts on a vehicle that the scenario's world declares; scenario 'sign' "
                                              "declares none"),
    ("trials --sign 3", "unrecognized arguments: --sign 3"),
    # scenarios and metrics
    ("trial --target parking_lot", "invalid choice"),
    ("trial --target cross_traffic --scenario-param cars=9", "parameter 'cars' must be an int in [1, 4]"),
    ("trial --scenario-param cars=2", "scenario 'sign' has no parameter(s) ['cars']"),
    ("trial --target stale_map --scenario-param case=gone", "parameter 'case' must be one of ['mapped', 'moved'"),
    ("trial --target stale_map --scenario-param case=moved --scenario-param shift_m=0.0", "needs |shift_m| >= 0.1 m"),
    ("trial --scenario-param cars", "--scenario-param takes KEY=VALUE"),
    ("trial --metric comfort", "unknown metric(s) ['comfort']"),
    ("scorecard --defence raw --target drive", "a battery runs in a scenario that approaches a stop sign"),
    ("bench sim --traffic-cars 9", "--traffic-cars must be in 1..4"),
    ("trial --sped 1.0", "unrecognized arguments: --sped"),
    # estimator options
    ("trial --estimator odca --estimator-option flavour=1", "no option(s) ['flavour']"),
    ("trial --estimator odca --estimator-option checkpoint={tmp}/nowhere", "no ODCA checkpoint"),
    ("trial --estimator odca --estimator-option checkpoint={ckpt}", "corrupt"),
    ("trial --estimator-option checkpoint=x", "raw"),
    ("trials --table --estimator-option checkpoint=x", "name the estimator"),
    ("trials --plugin {defences.py} --estimator tolerant --estimator-option tol_m=abc",
     "option tol_m must be a number"),
    ("trials --plugin {defences.py} --estimator picky", "cannot be built: RuntimeError: no GPU here"),
    # attack settings and schedules
    ("trial --attack depth_bias --attack-param depth_bias.trigger=at_time --attack-param depth_bias.start_s=1000",
     "start_s must be in [0.0, 120.0]"),
    ("trial --attack depth_bias --attack-param depth_bias.start_s=2", "start_s applies to trigger 'at_time'"),
    ("trial --attack depth_bias --attack-param depth_bias.trigger=sometimes", "trigger must be one of"),
    ("trial --attack frustum_spoof --attack-param frustum_spoof.scale_box=3", "scale_box must be true or false"),
    ("trial --attack depth_bias --attack-param bias_m=1", "takes NAME.KEY=VALUE"),
    ("trial --attack-param depth_bias.bias_m=1", "this command runs no attack"),
    ("trials --plugin {defences.py} --attack slow_start", "slow_start"),
    # plug-ins
    ("trial --plugin {tmp}/nowhere.py", "no such file"),
    ("trial --plugin {tmp}", "is a folder, not a file"),
    ("trial --plugin {bad.toml}", "is not a Python file"),
    ("trial --plugin {plugin_broken.py}", "failed to import: RuntimeError: boom"),
    ("trial --plugin {incomplete.py}", "class Incomplete (an estimator?) lacks would_pass()"),
    ("list --plugin", "--plugin needs a file"),
    # a scenario's or a car stage's declarations, checked before any simulator is built
    ("trial --plugin {worlds.py} --target clashing_truth", "declares the column 'd_true', which racf's step log"),
    ("trial --plugin {worlds.py} --target far_start", "options['run_up_m'] for sign 2 must be in [0.3,"),
    ("trial --plugin {worlds.py} --target clashing_stage", "car stage 'loud' declares the column 'brake'"),
    ("trial --plugin {worlds.py} --target unknown_stage", "unknown car stage 'cruise_control'"),
    ("trial --plugin {worlds.py} --target unsupervisable --supervisor", "supervisor: car stage 'quiet' publishes no "
                                                                        "typed track"),
    # specs
    ("sweep {tmp}/nowhere.toml", "no sweep spec"),
    ("sweep {bad.toml}", "not valid TOML"),
    ("sweep {empty.toml}", "no [space]"),
    ("sweep {nospace.toml}", "no [space]"),
    ("sweep {wrongtype.toml}", "repeats must be an int"),
    ("sweep --attack patch_occlusion --estimator kalman", "space.estimator"),
    ("sweep --attack none --estimator odca --estimator-option odca.checkpoint={ckpt}", "corrupt"),
    ("sweep {schedule.toml}", "start_s must be in"),
    # output folders
    ("trials -n 1 --out {plugin_broken.py}/results", "is a file, not a folder"),
    ("sweep smoke.toml --out /proc/racf-results", "/proc is not writable"),
    ("falsify --defence odca --out /proc/racf-results", "/proc is not writable"),
    ("collect --out {bad.toml}/data", "is a file, not a folder"),
    # datasets, checkpoints, recordings, cases
    ("bench --dataset {tmp}/nowhere", "nowhere"),
    ("bench --dataset {data_corrupt}", "data_corrupt"),
    ("train --dataset {tmp}/nowhere", "is not a racf dataset folder"),
    ("evaluate --dataset {tmp}/nowhere", "is not a racf dataset folder"),
    ("train --dataset {data_corrupt}", "corrupt dataset"),
    ("evaluate --checkpoint {tmp}/nowhere --dataset {tmp}/nowhere", "nowhere"),
    ("view {tmp}/nowhere.rrd", "nowhere.rrd"),
    ("view {bad.rrd}", "bad.rrd"),
    ("replay-case {tmp}/nowhere.json", "no case file"),
    ("replay-case {bad.toml}", "not a racf case file"),
    ("replay-case {tmp}", "no case files"),
    ("replay-case --defence tinfoil {bad.toml}", "unknown defence"),
    ("replay-case --suite --reseed -1", "--reseed must be in"),
    # bags and the defence service
    ("bag-info {tmp}/nowhere", "does not exist"),
    ("replay-bag {bad.toml}", "is a file; a rosbag2 is the folder"),
    ("replay-bag {tmp}", "is not a readable rosbag2"),
    ("replay-bag {tmp} --mapping {bad.toml}", "not valid TOML"),
    ("replay-bag {tmp} --attack lidar_spoof", "cannot act on a recording"),
    ("replay-bag {tmp} --attack depth_bias --attack-param lidar_spoof.range_m=1", "--attack-param names attack(s)"),
    ("export-bag {tmp}", "exists; remove it or choose another path"),
    ("serve --defence tinfoil", "unknown defence 'tinfoil'"),
    ("serve --estimator-option checkpoint=x", "name it with --defence"),
    ("trial --estimator-endpoint localhost:5555", "estimator_endpoint must be tcp://HOST:PORT"),
    ("trial --setting attack+odca --estimator-endpoint tcp://127.0.0.1:9 --estimator-timeout-ms 100",
     "nothing listens there; start one with `racf serve --bind tcp://127.0.0.1:9 --defence odca`"),
    ("trial --estimator-timeout-ms 20", "--estimator-timeout-ms applies with --estimator-endpoint"),
    ("trial --estimator-fallback odca", "--estimator-fallback applies with --estimator-endpoint"),
    ("trial --estimator-endpoint tcp://127.0.0.1:9 --estimator-fallback bogus",
     "estimator_fallback must be 'raw' (the car's own depth, unrepaired) or an estimator"),
    ("trial --target lead_vehicle --scenario-param broadcast=maybe", "parameter 'broadcast' must be one of ['off', 'on']"),
    ("trial --setting clean+radio_forge --attack-param radio_forge.ahead_m=50", "ahead_m must be in [-10, 10]"),
    ("trial --service-keys {keys}", "--service-keys applies with --estimator-endpoint"),
    ("trial --service-car a", "--service-car applies with --estimator-endpoint"),
    ("trial --estimator-endpoint tcp://127.0.0.1:9 --service-car a", "--service-car names a car of the key folder"),
    ("trial --estimator-endpoint tcp://127.0.0.1:9 --service-keys {tmp}/nowhere", "make a key folder with"),
    ("trial --setting clean+link_drop", "link_drop attacks the link to a defence service"),
    ("trial --setting clean+link_delay --estimator-endpoint tcp://127.0.0.1:9 --attack-param link_delay.delay_ms=-5",
     "delay_ms must be a number in [0.0, 5000.0]"),
    ("serve --bind tcp://0.0.0.0:5555", "is reachable from other machines: serve it with --keys DIR"),
    ("serve --keys {tmp}/nowhere", "make a key folder with `racf serve keys"),
    ("serve keys {keys}", "keys are never overwritten"),
    ("serve --idle-s 0", "--idle-s must be >= 1.0"),
    ("bag-info {corrupt_bag}", "the recording is truncated or corrupt: copy it again"),
    ("replay-bag {corrupt_bag}", "the recording is truncated or corrupt: copy it again"),
    ("bench guard --slowdown 9", "--slowdown must be in [1, 5]"),
    ("bench guard --store --slowdown 1.2", "--store keeps a real measurement"),
    ("bench paired --baseline {tmp}", "--baseline must be a racf checkout"),
    ("bench paired --baseline . --setting warp", "--setting: a setting starts with"),
    # searches
    ("falsify --defence tinfoil", "unknown defence 'tinfoil'"),
    ("falsify --defence odca --attack laser", "unknown attack"),
    ("falsify --defence odca --space {bad.toml}", "not valid TOML"),
    ("falsify --defence odca --space {tmp}/nowhere.toml", "cannot read the space"),
    ("falsify --defence odca --attack stealth_ramp --space {space_bound.toml} --out {tmp}/falsified",
     "the space's attack.stealth_ramp.rate_mps = 30.0 is out of what the episode takes"),
    ("falsify --defence odca --budget 0", "budget must be"),
    ("falsify --defence odca --seeds 0", "--seeds must be"),
    ("falsify --defence odca --sampler annealing", "invalid choice"),
]

#: Plug-ins for the corpus: a defence with a typed option, one whose constructor fails, and an
#: attack whose schedule the episode cannot take.
_DEFENCES = '''
from racf.controllers.estimators import RawDepthEstimator
from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule


class Tolerant(RawDepthEstimator):
    name = "tolerant"

    def __init__(self, tol_m: float = 0.3):
        super().__init__()
        self.tol_m = tol_m


class Picky(RawDepthEstimator):
    name = "picky"

    def __init__(self):
        raise RuntimeError("no GPU here")


class SlowStart(AttackWrapper):
    """Opens its window 200 s in: more than any episode lasts, and more than the schedule takes."""
    name = "slow_start"

    def __init__(self, env, **schedule):
        super().__init__(env, AttackSchedule(**{**schedule, "trigger": "at_time", "start_s": 200.0}))
'''

#: Scenarios a user may get wrong: a truth column named like racf's, a run-up the sign does not allow,
#: a car stage whose column is racf's, a stage nobody registered.
_WORLDS = '''
import dataclasses

from racf.experiments.car.stage import CarStage, StageColumn
from racf.experiments.scenarios import Scenario
from racf.sim.world.manager import TruthColumn, WorldManager


class Clashing(WorldManager):
    name = "clashing"

    def columns(self):
        return (TruthColumn("d_true", "m", "mine"),)


class ClashingTruth(Scenario):
    name = "clashing_truth"

    def world(self, spec, values):
        return (Clashing(),)


class FarStart(Scenario):
    name = "far_start"

    def run_up(self, spec):
        return 9.0


class Loud(CarStage):
    name = "loud"
    columns = (StageColumn("brake", "bool", "mine"),)

    def step(self, view):
        raise AssertionError("never built")


class _Staged(Scenario):
    stage = ""

    def plan(self, spec, values, draft):
        mission = dataclasses.replace(draft.mission, stages=(self.stage,))
        return self.replace(draft, mission=mission)


class ClashingStage(_Staged):
    name = "clashing_stage"
    stage = "loud"


class UnknownStage(_Staged):
    name = "unknown_stage"
    stage = "cruise_control"


class Quiet(CarStage):
    name = "quiet"

    def step(self, view):
        raise AssertionError("never built")


class Unsupervisable(_Staged):
    name = "unsupervisable"
    stage = "quiet"
'''

_INCOMPLETE = '''
class Incomplete:
    name = "incomplete"

    def reset(self):
        pass

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0):
        return sample.d_meas

    def diagnostics(self):
        return {}
'''


def make_files(root: Path) -> dict[str, str]:
    """Writes the corpus's files into ``root``; returns {placeholder: path}."""
    (root / "data_corrupt").mkdir()
    (root / "data_corrupt" / "dataset.parquet").write_bytes(b"PAR1 garbage")
    (root / "data_corrupt" / "split.json").write_text("{}")
    (root / "ckpt").mkdir()
    (root / "ckpt" / "odca.json").write_text("{not json")
    (root / "ckpt" / "head.npz").write_bytes(b"no weights")
    texts = {"bad.toml": "name = [unclosed\n", "empty.toml": "", "nospace.toml": 'name = "x"\nmode = "grid"\n',
             "wrongtype.toml": 'name = "x"\nrepeats = "two"\n[space]\nattack = ["none"]\n',
             "schedule.toml": 'name = "x"\n[space]\nattack = ["depth_bias"]\n[params.depth_bias]\n'
                              'trigger = ["at_time"]\nstart_s = [500.0]\n',
             "space_bound.toml": "[attack.stealth_ramp]\nrate_mps = {low = 0.1, high = 30.0}\n",
             "bad.rrd": "not a recording", "plugin_broken.py": "raise RuntimeError('boom')\n",
             "defences.py": _DEFENCES, "incomplete.py": _INCOMPLETE, "worlds.py": _WORLDS}
    for name, text in texts.items():
        (root / name).write_text(text)
    from racf.experiments.link.curve import make_keys

    make_keys(root / "keys")
    (root / "corrupt_bag").mkdir()
    (root / "corrupt_bag" / "metadata.yaml").write_text(_BAG_METADATA)
    (root / "corrupt_bag" / "corrupt_bag.mcap").write_bytes(bytes(range(256)) * 16)  # no MCAP magic
    return {name: str(root / name) for name in ["data_corrupt", "ckpt", "keys", "corrupt_bag", *texts]}


#: A rosbag2's metadata naming one MCAP file (the corpus writes that file as bytes that are no MCAP).
_BAG_METADATA = """rosbag2_bagfile_information:
  version: 9
  storage_identifier: mcap
  duration: {nanoseconds: 1000000000}
  starting_time: {nanoseconds_since_epoch: 0}
  message_count: 1
  topics_with_message_count:
  - message_count: 1
    topic_metadata: {name: /scan, offered_qos_profiles: [], serialization_format: cdr,
                     type: sensor_msgs/msg/LaserScan, type_description_hash: ''}
  compression_format: ''
  compression_mode: ''
  relative_file_paths: [corrupt_bag.mcap]
  files:
  - {path: corrupt_bag.mcap, starting_time: {nanoseconds_since_epoch: 0}, duration: {nanoseconds: 1000000000},
     message_count: 1}
  custom_data: {}
  ros_distro: rosbags
"""


def mistakes_markdown() -> str:
    """The corpus as the CLI reference page's table."""
    lines = ["## What racf says to a mistake", "",
             "Each of these exits with code 2 and one line on stderr that holds the words shown, before any "
             "episode runs (the tests run every one). `{tmp}` is a scratch folder; the other placeholders are "
             "files the tests write there (`racf.experiments.cli.mistakes.make_files`). An episode whose code "
             "raises (a plug-in's fault) exits 1 with one line naming the part, the exception and the episode, "
             "the traceback in `failures.log` under the results folder; Ctrl-C or SIGTERM exits 130 with "
             "\"N of M episodes stored; run the same command again to resume\".", "",
             "| command | the line says |", "|---|---|"]
    lines += [f"| `racf {command}` | {words.replace('|', '/')} |" for command, words in MISTAKES]
    return "\n".join(lines)
