"""The corpus of a user's mistakes: every one exits 2 with one line naming the problem and what is
allowed, before any work, and never with a traceback."""

from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from racf.experiments.cli import main


def _files(root: Path) -> dict[str, str]:
    (root / "corrupt.parquet").write_bytes(b"not parquet")
    (root / "data_corrupt").mkdir()
    (root / "data_corrupt" / "dataset.parquet").write_bytes(b"PAR1 garbage")
    (root / "ckpt").mkdir()
    (root / "ckpt" / "odca.json").write_text("{not json")
    (root / "ckpt" / "head.npz").write_bytes(b"no weights")
    (root / "bad.toml").write_text("name = [unclosed\n")
    (root / "empty.toml").write_text("")
    (root / "nospace.toml").write_text('name = "x"\nmode = "grid"\n')
    (root / "wrongtype.toml").write_text('name = "x"\nrepeats = "two"\n[space]\nattack = ["none"]\n')
    (root / "bad.rrd").write_bytes(b"not a recording")
    (root / "plugin_broken.py").write_text("raise RuntimeError('boom')\n")
    return {k: str(root / k) for k in ("corrupt.parquet", "data_corrupt", "ckpt", "bad.toml", "empty.toml",
                                       "nospace.toml", "wrongtype.toml", "bad.rrd", "plugin_broken.py")}


#: (command line with {placeholders}, words the message must hold)
CORPUS = [
    ("trial --speed fast", "speed"),
    ("trial --sign 9", "sign"),
    ("trials -n 0", ">= 1"),
    ("trial --rho 2", "rho"),
    ("trial --estimator kalman", "estimator must be one of"),
    ("trial --attack laser", "unknown attack"),
    ("trial --detector yolo", "invalid choice"),
    ("trial --setting attack --target obstacle --sign 0", "cannot act on target 'obstacle'"),
    ("trial --estimator odca --estimator-option flavour=1", "no option(s) ['flavour']"),
    ("trial --estimator odca --estimator-option checkpoint={tmp}/nowhere", "no ODCA checkpoint"),
    ("trial --estimator odca --estimator-option checkpoint={ckpt}", "corrupt"),
    ("trial --estimator-option checkpoint=x", "raw"),
    ("trials --table --estimator-option checkpoint=x", "name the estimator"),
    ("trial --plugin {tmp}/nowhere.py", "no such Python file"),
    ("trial --plugin {plugin_broken.py}", "failed to import: RuntimeError: boom"),
    ("list --plugin", "--plugin needs a file"),
    ("sweep {tmp}/nowhere.toml", "no sweep spec"),
    ("sweep {bad.toml}", "not valid TOML"),
    ("sweep {empty.toml}", "no [space]"),
    ("sweep {nospace.toml}", "no [space]"),
    ("sweep {wrongtype.toml}", "repeats must be an int"),
    ("sweep --attack patch_occlusion --estimator kalman", "space.estimator"),
    ("sweep --attack none --estimator odca --estimator-option odca.checkpoint={ckpt}", "corrupt"),
    ("bench --dataset {tmp}/nowhere", "nowhere"),
    ("bench --dataset {data_corrupt}", "data_corrupt"),
    ("view {tmp}/nowhere.rrd", "nowhere.rrd"),
    ("view {bad.rrd}", "bad.rrd"),
    ("evaluate --checkpoint {tmp}/nowhere --dataset {tmp}/nowhere", "nowhere"),
    ("falsify --defence tinfoil", "unknown defence 'tinfoil'"),
    ("falsify --defence odca --attack laser", "unknown attack"),
    ("falsify --defence odca --space {bad.toml}", "not valid TOML"),
    ("falsify --defence odca --space {tmp}/nowhere.toml", "cannot read the space"),
    ("falsify --defence odca --budget 0", "budget must be"),
    ("falsify --defence odca --seeds 0", "--seeds must be"),
    ("falsify --defence odca --sampler annealing", "invalid choice"),
    ("replay-case {tmp}/nowhere.json", "no case file"),
    ("replay-case {bad.toml}", "not a racf case file"),
    ("replay-case {tmp}", "no case files"),
    ("replay-case --defence tinfoil {bad.toml}", "unknown defence"),
    ("replay-case --suite --reseed -1", "--reseed must be in"),
]


@pytest.mark.parametrize("command, words", CORPUS, ids=[c for c, _ in CORPUS])
def test_a_mistake_exits_2_with_one_line(command, words, tmp_path, plugin_env):
    names = _files(tmp_path)
    line = command.replace("{tmp}", str(tmp_path))
    for key, path in names.items():
        line = line.replace("{" + key + "}", path)
    argv = line.split()
    err, out = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out):
        try:
            code = main(argv)
        except SystemExit as exit_:  # argparse's own errors
            code = exit_.code
    message = err.getvalue().strip()
    assert code == 2, (command, message, out.getvalue()[-300:])
    assert "Traceback" not in message
    last = message.splitlines()[-1] if message else ""
    assert words in last, (command, message)
    assert len([line for line in message.splitlines() if line.startswith("racf")]) == 1, message


def test_random_mode_without_rho_runs_on_its_own_valid_default():
    from racf.experiments.sweeps.spec import parse_spec

    spec = parse_spec('mode = "random"\nn = 3\n[space]\nattack = ["patch_occlusion"]\n')
    assert spec.space["rho"] == [0.95, 0.95]
    assert {e.rho for e in spec.episodes()} == {(0.95, 0.95)}
