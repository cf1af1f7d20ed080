"""`make mutate`: cosmic-ray over the link's code and the car's parts, resumable, then its score.

The session lives in outputs/mutation/: a run interrupted resumes where it stopped (`make mutate`
again), and one whose modules, runner or configuration changed since starts afresh (its fingerprint
names what made the mutants). Where only the tests changed, the mutants stand and every survivor
is tried again against the new tests (a test added to kill one is checked to kill it). The score is
killed / (all - the equivalent mutants argued in equivalent.toml), printed with every survivor that
is not argued, so that one can be killed by a new test.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import sqlite3
import subprocess
import sys
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CONFIG = HERE / "cosmic-ray.toml"
#: `make mutate MODULES="a.py b.py"`: a session of its own over some of the modules (two checkouts can
#: then share a machine's cores between them).
ONLY = os.environ.get("MUTATE_MODULES", "").split()
OUT = ROOT / "outputs" / "mutation" / ("only-" + "-".join(Path(m).stem for m in ONLY) if ONLY else "")
SESSION = OUT / "session.sqlite"
#: The score the link's tests must keep over its non-equivalent mutants.
GOAL = 0.90


def _modules() -> list[str]:
    every = tomllib.loads(CONFIG.read_text())["cosmic-ray"]["module-path"]
    unknown = [m for m in ONLY if m not in every]
    if unknown:
        raise SystemExit(f"make mutate: {unknown[0]} is not among the modules of {CONFIG.name}: {', '.join(every)}")
    return ONLY or every


def fingerprint(tests: bool = False) -> str:
    """What made the mutants (the configuration, the modules, the runner), or with ``tests`` the tests
    that judge them."""
    sys.path.insert(0, str(HERE))
    from run_tests import TESTS

    files = sorted({ROOT / t for tests in TESTS.values() for t in tests if (ROOT / t).exists()}
                   | {ROOT / "tests" / "experiments" / "link" / "fake_service.py"} if tests else
                   {CONFIG, HERE / "run_tests.py", HERE / "forkserver.py", *(ROOT / m for m in _modules())})
    digest = hashlib.sha256()
    for path in files:
        digest.update(str(path.relative_to(ROOT)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def _tool(name: str, *args: str) -> None:
    subprocess.run([str(Path(sys.executable).parent / name), *args], cwd=ROOT, check=True)


def main() -> int:
    dirty = subprocess.run(["git", "status", "--porcelain", "--", *_modules()], cwd=ROOT, capture_output=True,
                           text=True).stdout.strip()
    if dirty:
        print(f"make mutate: commit or stash the changes to {dirty.split()[-1]} first (a mutant is found by git diff)",
              file=sys.stderr)
        return 2
    OUT.mkdir(parents=True, exist_ok=True)
    stamp, judged = OUT / "fingerprint", OUT / "tests-fingerprint"
    made_by, tests = fingerprint(), fingerprint(tests=True)
    # The configuration as run: its test command in this Python (a bare `python` may be another one).
    config = OUT / "cosmic-ray.toml"
    text = CONFIG.read_text().replace('test-command = "python ', f'test-command = "{sys.executable} ')
    config.write_text(re.sub(r"module-path = \[.*?\]", "module-path = " + json.dumps(_modules()), text, flags=re.S))
    if not SESSION.exists() or not stamp.exists() or stamp.read_text() != made_by:
        SESSION.unlink(missing_ok=True)
        _tool("cosmic-ray", "init", str(config), str(SESSION), "--force")
        _tool("cr-filter-operators", str(SESSION), str(config))
        stamp.write_text(made_by)
    else:
        print(f"make mutate: resuming {SESSION} (made by {made_by})")
    skip_argued()
    with forkserver():
        failing = baseline()
        if failing:
            print(f"make mutate: {failing} fail without any mutant: fix them first (every mutant would look killed)",
                  file=sys.stderr)
            return 1
        if judged.exists() and judged.read_text() != tests:
            recheck(config)
        judged.write_text(tests)
        _tool("cosmic-ray", "exec", str(config), str(SESSION))
    return report()


def _argued() -> set[tuple[str, str, int]]:
    equivalent = tomllib.loads((HERE / "equivalent.toml").read_text()).get("mutant", [])
    return {(e["module"], e["operator"], e["line"]) for e in equivalent}


def skip_argued() -> None:
    """Marks the pending mutants argued equivalent in equivalent.toml as skipped: they would survive,
    and they count neither way, so their runs (every test of their module) are saved."""
    db = sqlite3.connect(SESSION)
    argued = _argued()
    pending = db.execute("""select m.job_id, m.module_path, m.operator_name, m.start_pos_row from mutation_specs m
                            where m.job_id not in (select job_id from work_results)""").fetchall()
    skipped = [job for job, module, operator, row in pending if (module, operator, row) in argued]
    db.executemany("insert into work_results (worker_outcome, output, test_outcome, diff, job_id) "
                   "values ('SKIPPED', 'argued equivalent in equivalent.toml', null, null, ?)",
                   [(job,) for job in skipped])
    db.commit()
    if skipped:
        print(f"make mutate: {len(skipped)} mutants argued equivalent are not run")


def baseline() -> str | None:
    """The tests of each module on the code as it is: they must pass, or no kill means anything."""
    for module in _modules():
        run = subprocess.run([sys.executable, str(HERE / "run_tests.py"), "--baseline", module], cwd=ROOT,
                             capture_output=True, text=True)
        if run.returncode != 0:
            return f"the tests of {module} ({run.stdout.strip()})"
    print(f"make mutate: the tests of {len(_modules())} modules pass without a mutant")
    return None


@contextlib.contextmanager
def forkserver():
    """A warm process that forks each test run (tests/mutation/forkserver.py), for the runs inside."""
    import os

    # A Unix socket's path holds at most 107 bytes: a session folder named after several modules is longer.
    import tempfile

    path = Path(tempfile.gettempdir()) / f"racf-mutate-{hashlib.sha256(str(OUT).encode()).hexdigest()[:12]}.sock"
    path.unlink(missing_ok=True)
    proc = subprocess.Popen([sys.executable, str(HERE / "forkserver.py"), str(path)], cwd=ROOT, stdout=subprocess.PIPE,
                            text=True)
    try:
        if proc.stdout.readline().strip() != "ready":
            raise RuntimeError("the mutation fork server did not start")
        os.environ["RACF_MUTATION_FORKSERVER"] = str(path)
        yield
    finally:
        os.environ.pop("RACF_MUTATION_FORKSERVER", None)
        path.unlink(missing_ok=True)
        proc.wait(10)


def recheck(config: Path) -> None:
    """Tries every survivor again against the tests as they are now; a kill is written to the session."""
    db = sqlite3.connect(SESSION)
    argued = _argued()
    survivors = [s for s in db.execute("""select m.job_id, m.module_path, m.operator_name, m.occurrence, m.start_pos_row
                                          from mutation_specs m join work_results r on r.job_id = m.job_id
                                          where r.test_outcome = 'SURVIVED'""").fetchall()
                 if (s[1], s[2], s[4]) not in argued]  # an argued one would survive again
    command = tomllib.loads(config.read_text())["cosmic-ray"]["test-command"]
    print(f"make mutate: the tests changed; trying the {len(survivors)} survivors again")
    for job_id, module, operator, occurrence, _ in survivors:
        run = subprocess.run([str(Path(sys.executable).parent / "cosmic-ray"), "mutate-and-test", module, operator,
                              str(occurrence), command], cwd=ROOT, capture_output=True, text=True)
        result = json.loads(run.stdout.strip().splitlines()[-1])
        if result.get("test_outcome") == "killed":
            db.execute("update work_results set test_outcome = 'KILLED', output = ? where job_id = ?",
                       (str(result.get("output", "")), job_id))
            db.commit()
            print(f"  killed now: {module} {operator} (occurrence {occurrence})")


def report() -> int:
    db = sqlite3.connect(SESSION)
    rows = db.execute("""select m.module_path, m.operator_name, m.occurrence, m.start_pos_row, r.test_outcome,
                                r.worker_outcome, coalesce(r.output, '')
                         from mutation_specs m join work_results r on r.job_id = m.job_id""").fetchall()
    errors = [r for r in rows if "RUNNER ERROR" in r[6]]  # no verdict: neither killed nor survived
    rows = [r for r in rows if "RUNNER ERROR" not in r[6]]
    pending = db.execute("select count(*) from work_items where job_id not in (select job_id from work_results)"
                         ).fetchone()[0]
    tried = [r for r in rows if r[5] != "SKIPPED"]
    argued = _argued()
    survivors = [r for r in tried if r[4] == "SURVIVED"]
    unargued = [r for r in survivors if (r[0], r[1], r[3]) not in argued]
    killed = sum(r[4] == "KILLED" for r in tried)
    counted = len(tried) - (len(survivors) - len(unargued))
    score = killed / counted if counted else float("nan")
    print(f"mutants tried {len(tried)} (pending {pending}), killed {killed}, survived {len(survivors)} "
          f"({len(survivors) - len(unargued)} argued equivalent in tests/mutation/equivalent.toml)")
    by_module = {}
    for r in tried:
        k = by_module.setdefault(r[0], [0, 0])
        k[0] += r[4] == "KILLED"
        k[1] += 1
    for module, (k, n) in sorted(by_module.items()):
        print(f"  {module:<36} killed {k:>4} of {n:>4}")
    for r in unargued:
        print(f"  survived: {r[0]}:{r[3]} {r[1]} (occurrence {r[2]})")
    for r in errors:
        print(f"  no verdict: {r[0]}:{r[3]} {r[1]}: {r[6].strip()[:200]}")
    print(f"score {score:.3f} over the non-equivalent mutants (goal {GOAL:.2f})")
    (OUT / "score.json").write_text(json.dumps({"tried": len(tried), "pending": pending, "killed": killed,
                                                "survived": len(survivors), "argued": len(survivors) - len(unargued),
                                                "score": score if counted else None}, indent=2))
    return 0 if pending == 0 and not errors and score >= GOAL else 1


if __name__ == "__main__":
    sys.exit(report() if sys.argv[1:] == ["--report"] else main())
