"""The corpus of a user's mistakes (``racf.experiments.cli.mistakes``): every one exits 2 with one
line naming the problem and what is allowed, before any work, and never with a traceback; a
plug-in's fault exits 1, an interrupt 130, each with one line."""

from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout
import pytest

from racf.experiments.cli import main
from racf.experiments.cli.mistakes import MISTAKES, make_files


def _run(argv: list[str]) -> tuple[int, str, str]:
    err, out = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out):
        try:
            code = main(argv)
        except SystemExit as exit_:  # argparse's own errors
            code = exit_.code
    return code, err.getvalue().strip(), out.getvalue()


def test_the_corpus_is_large_and_names_each_mistake_once():
    commands = [c for c, _ in MISTAKES]
    assert len(commands) >= 40 and len(set(commands)) == len(commands)


@pytest.mark.parametrize("command, words", MISTAKES, ids=[c for c, _ in MISTAKES])
def test_a_mistake_exits_2_with_one_line(command, words, tmp_path, plugin_env):
    names = make_files(tmp_path)
    line = command.replace("{tmp}", str(tmp_path))
    for key, path in names.items():
        line = line.replace("{" + key + "}", path)
    code, message, out = _run(line.split() + (["--out", str(tmp_path / "out")] if _runs(line) else []))
    assert code == 2, (command, message, out[-300:])
    assert "Traceback" not in message
    assert len(message.splitlines()) == 1 and message.startswith("racf"), message
    prefix = message.split(":", 1)[0] + ":"
    assert prefix not in message[len(prefix):], message  # the command's prefix once
    assert words in message, (command, message)
    assert not (tmp_path / "out" / "parts").exists()  # refused before any episode


def _runs(line: str) -> bool:
    """Whether the command runs episodes into a default folder the test must not write."""
    return line.split()[0] in ("trial", "trials", "sweep") and "--out" not in line


def test_a_folder_the_user_cannot_write_is_refused_before_any_work(tmp_path, monkeypatch, capsys):
    import tempfile

    def refused(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "TemporaryFile", refused)  # as for a user without write access (tests run as root)
    assert main(["trials", "-n", "1", "--out", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.splitlines() == [err] and f"{tmp_path} is not writable (Permission denied)" in err
    assert not (tmp_path / "results").exists()


def test_a_plugin_that_raises_in_an_episode_exits_1_naming_it_with_the_traceback_in_a_log(tmp_path, plugin_env):
    plugin = tmp_path / "flaky.py"
    plugin.write_text(
        "from racf.controllers.estimators import RawDepthEstimator\n\n\n"
        "class Flaky(RawDepthEstimator):\n    name = 'flaky'\n\n"
        "    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0):\n"
        "        raise ZeroDivisionError('flaky divided by zero')\n")
    code, message, _ = _run(["trial", "--plugin", str(plugin), "--estimator", "flaky", "--sign", "1",
                             "--out", str(tmp_path / "out")])
    assert code == 1 and len(message.splitlines()) == 1, message
    for words in ("estimator plug-in 'flaky'", "ZeroDivisionError: flaky divided by zero", "clean+flaky sign1",
                  str(tmp_path / "out" / "failures.log")):
        assert words in message, message
    assert "Traceback (most recent call last)" in (tmp_path / "out" / "failures.log").read_text()


def test_an_interrupt_exits_130_with_one_line(monkeypatch, tmp_path):
    import racf.experiments.cli.trials as trials

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(trials, "_trials", interrupted)
    code, message, _ = _run(["trials", "-n", "1", "--out", str(tmp_path)])
    assert code == 130 and message == "racf trials: interrupted; nothing half-written was kept"


def test_random_mode_without_rho_runs_on_its_own_valid_default():
    from racf.experiments.sweeps.spec import parse_spec

    spec = parse_spec('mode = "random"\nn = 3\n[space]\nattack = ["patch_occlusion"]\n')
    assert spec.space["rho"] == [0.95, 0.95]
    assert {e.rho for e in spec.episodes()} == {(0.95, 0.95)}
