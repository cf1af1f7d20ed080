"""Editors and type checkers resolve ``racf.*`` to the files in the checkout: the editable install
is a plain ``.pth`` path to a tree of links that setuptools builds from pyproject's package-dir
(``editable_mode=strict``), not an import hook that static analysis cannot run. jedi (Pylance and pyright follow the same path entries) is asked from
a fresh interpreter outside the repository, as an editor would ask."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_ASK = """
import json, jedi, sys
source = "import racf.sim.env\\nimport racf.odca.online\\nfrom racf.controllers import DistanceEstimator\\n"
script = jedi.Script(source, path=sys.argv[1])
found = {}
for line, column, name in ((1, 17, "racf.sim.env"), (2, 17, "racf.odca.online"), (3, 30, "DistanceEstimator")):
    found[name] = [str(n.module_path) for n in script.goto(line, column, follow_imports=True)]
print(json.dumps(found))
"""


def test_jedi_resolves_racf_and_a_plugins_imports_to_the_checkouts_files(tmp_path):
    plugin = tmp_path / "my_defence.py"  # a plug-in of the user's, outside the repository
    done = subprocess.run([sys.executable, "-I", "-c", _ASK, str(plugin)], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    found = {name: [os.path.realpath(p) for p in paths] for name, paths in json.loads(done.stdout).items()}
    assert found["racf.sim.env"] == [str(ROOT / "sim" / "env" / "__init__.py")]
    assert found["racf.odca.online"] == [str(ROOT / "odca" / "online.py")]
    assert found["DistanceEstimator"]
    assert all(p.startswith(str(ROOT / "controllers")) for p in found["DistanceEstimator"])
