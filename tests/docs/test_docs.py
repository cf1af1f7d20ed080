"""The documentation cannot go stale: a short README, generated reference pages that match the
code, a site that builds strictly, and every fenced Python and shell block run, except those
marked ``<!-- illustrative: why -->`` (and ``<!-- slow -->`` ones, which run with -m slow)."""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
from contextlib import redirect_stdout
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
_FENCE = re.compile(r"(?:^<!-- (illustrative|slow|prints)[^>]*-->\n)?^```(\w*)\n(.*?)^```", re.M | re.S)
_RUN = ("python", "bash")


def blocks(page: Path) -> list[tuple[str, str, str]]:
    """(mark: '' | 'illustrative' | 'slow' | 'prints', language, code) of each fenced block of a page."""
    return [(m.group(1) or "", m.group(2), m.group(3)) for m in _FENCE.finditer(page.read_text())]


def _runnable(page: Path, slow: bool) -> dict[str, list[tuple[str, str | None]]]:
    """The blocks to run by language, each with what the page says it prints: a block marked
    ``<!-- prints -->`` right after it (``...`` stands for any text, as in doctest), or None."""
    out: dict[str, list[tuple[str, str | None]]] = {"python": [], "bash": []}
    found = blocks(page)
    for i, (mark, lang, code) in enumerate(found):
        if lang in _RUN and mark not in ("illustrative", "prints") and (slow or mark != "slow"):
            after = found[i + 1] if i + 1 < len(found) else None
            out[lang].append((code, after[2] if after is not None and after[0] == "prints" else None))
    return out


def _prints(expected: str | None, got: str, where: str) -> None:
    """The output a page states, against what its block printed (``...`` matches anything)."""
    import doctest

    if expected is None:
        return
    checker = doctest.OutputChecker()
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    assert checker.check_output(expected, got, flags), (
        f"{where} prints other than the page says:\n--- the page\n{expected}--- printed\n{got}")


def test_the_readme_is_short():
    assert (ROOT / "README.md").stat().st_size <= 15_000


def test_no_page_names_a_path_outside_the_repository():
    offenders = [str(p.relative_to(ROOT)) for p in PAGES if re.search(r"\.\./shared|/work/", p.read_text())]
    assert offenders == []


def test_the_generated_reference_pages_are_current():
    from racf.experiments.cli.reference import PAGES as GENERATED

    stale = [name for name, make in GENERATED.items() if (ROOT / "docs" / name).read_text() != make()]
    assert stale == [], f"run `make docs` to regenerate {stale}"


def test_the_readmes_results_table_is_written_from_the_stored_results():
    from racf.experiments.cli.reference import readme_with_table

    text = (ROOT / "README.md").read_text()
    assert readme_with_table(text) == text, "run `make docs` to rewrite the README's results table"


def test_every_stated_output_follows_a_block_that_runs():
    for page in PAGES:
        found = blocks(page)
        for i, (mark, _, _) in enumerate(found):
            if mark == "prints":
                before = found[i - 1] if i else ("", "", "")
                assert i and before[1] in _RUN and before[0] != "illustrative", f"{page.name}: block {i + 1}"


def test_every_block_is_run_or_marked():
    counted = {"run": 0, "slow": 0, "illustrative": 0}
    for page in PAGES:
        for mark, lang, _ in blocks(page):
            if lang in _RUN:
                counted[mark or "run"] += 1
    assert counted["run"] >= 4 and counted["illustrative"] <= counted["run"] + counted["slow"] + 8, counted


def _run_page(page: Path, tmp_path: Path, slow: bool, monkeypatch) -> None:
    code = _runnable(page, slow)
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"),
           "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    for shared in ("examples", "docs"):  # pages name the examples and the stored results from the checkout's root
        (tmp_path / shared).symlink_to(ROOT / shared)
    monkeypatch.chdir(tmp_path)
    # A page's Python blocks share one namespace, in order, run as a script is (a spawned worker's
    # __main__ guard holds, as it does when a user pastes the block into a file).
    namespace: dict = {"__name__": "__main__"}
    for i, (block, expected) in enumerate(code["python"]):
        printed = io.StringIO()
        try:
            with redirect_stdout(printed):
                exec(compile(block, f"{page.name}:python block {i + 1}", "exec"), namespace)
        except Exception as err:  # name the page and the block
            pytest.fail(f"{page.name}: Python block {i + 1} failed: {type(err).__name__}: {err}\n{block}")
        _prints(expected, printed.getvalue(), f"{page.name}: Python block {i + 1}")
    import gymnasium as gym

    for made in [v for v in namespace.values() if isinstance(v, (gym.Env, gym.vector.VectorEnv))]:
        made.close()  # the pages' envs
    for block, expected in code["bash"]:
        done = subprocess.run(["bash", "-e", "-c", block], cwd=tmp_path, env=env, capture_output=True, text=True)
        assert done.returncode == 0, f"{page.name}: a shell block failed:\n{block}\n{done.stderr[-2000:]}"
        _prints(expected, done.stdout, f"{page.name}: shell block")


#: The pages whose blocks take longest (3-7 s each): in the slow run, so that the default run keeps under two
#: minutes on 2 cores; the README's and the plug-in guide's run in both.
_LONG_PAGES = {"docs/tutorials/attack.md", "docs/tutorials/falsify.md", "docs/tutorials/detector.md",
               "docs/tutorials/defence.md", "docs/tutorials/sweeps.md", "docs/tutorials/submit-a-card.md",
               "docs/concepts/traffic.md"}


@pytest.mark.parametrize("page", [pytest.param(p, marks=pytest.mark.slow) if str(p.relative_to(ROOT)) in _LONG_PAGES
                                  else p for p in PAGES if any(_runnable(p, False).values())],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_the_pages_code_runs(page, tmp_path, monkeypatch, plugin_env):
    _run_page(page, tmp_path, slow=False, monkeypatch=monkeypatch)


@pytest.mark.slow
@pytest.mark.parametrize("page", [p for p in PAGES if any(_runnable(p, True).values()) and
                                  _runnable(p, True) != _runnable(p, False)], ids=lambda p: str(p.relative_to(ROOT)))
def test_the_pages_slow_code_runs(page, tmp_path, monkeypatch, plugin_env):
    _run_page(page, tmp_path, slow=True, monkeypatch=monkeypatch)


@pytest.mark.slow  # mkdocs and mkdocstrings read the whole package: CI's slow stage builds it
def test_the_site_builds_strictly(tmp_path):
    mkdocs = Path(sys.executable).parent / "mkdocs"
    done = subprocess.run([str(mkdocs), "build", "--strict", "--site-dir", str(tmp_path / "site")], cwd=ROOT,
                          capture_output=True, text=True, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert done.returncode == 0, done.stderr[-3000:]
