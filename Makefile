# racf: the two commands are `make demo` (main job) and `make test` (tests).
# Both create .venv and install what is missing: the CPU build of torch first (a newer
# or unpinned torch would pull several GB of CUDA packages), then racf and its deps.

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# The development install is a tree of links to racf's files (setuptools' editable_mode=strict: a
# plain path that editors and type checkers follow, and nothing importable but racf). A file added
# or removed needs a new tree: the stamp is named after the packages' file list.
LAYOUT := $(shell find core sim odca controllers experiments assets -name __pycache__ -prune -o -type f -print 2>/dev/null | sort | cksum | cut -d' ' -f1)
STAMP := $(VENV)/.racf-installed-$(LAYOUT)
TORCH := torch==2.13.0
export MUJOCO_GL ?= egl
# Python caches compiled modules: a machine that turns that off (PYTHONDONTWRITEBYTECODE) makes
# every test process, spawned worker and `racf` subprocess compile racf and the tests again.
unexport PYTHONDONTWRITEBYTECODE

.PHONY: mutate browser demo test test-all check-slow check-speed docs bench bench-sim snapshot trials bench-detector clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -qq --upgrade pip

# -qq: errors only.
$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install -qq $(TORCH)
	rm -rf build/__editable__.racf-*
	$(PY) -m pip install -qq -e ".[test]" --config-settings editable_mode=strict
	rm -f $(VENV)/.racf-installed*
	touch $(STAMP)

# The story at one stop sign: clean, patch attack, attack + ODCA (table, three .rrd, one PNG).
demo: $(STAMP)
	$(VENV)/bin/racf demo --out outputs/demo

# The default run leaves out the checks marked slow (Ray, kill-and-resume, killed workers, the
# shipped cases replayed, bench-loop, full collection, PPO, the wheel in a fresh venv, the docs'
# slow blocks); `make test-all` runs everything, `make check-slow` only those. CI runs both. It runs one test file per core (pytest-xdist), each process on one thread: left to
# their defaults, torch, OpenMP and Mesa start a thread per core in every process.
SINGLE_THREAD := OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 LP_NUM_THREADS=0
test: $(STAMP)
	$(SINGLE_THREAD) $(PY) -m pytest -q -n auto --dist loadfile --durations=10

test-all: $(STAMP)
	$(PY) -m pytest -q -m "" --durations=10

# Debian's Chromium for the browser test (tests/docs/test_site_browser.py): the machine's package,
# never a browser that pip or Playwright downloads. Installs it where it is missing (as root).
browser:
	@command -v chromium >/dev/null || (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null)

# The slow checks, spread test by test over the cores (a page's slow blocks are one test each).
check-slow: $(STAMP) browser
	$(SINGLE_THREAD) $(PY) -m pytest -q -m slow -n auto --dist load --durations=15

# The speed guard: the closed loop's step cost over bare physics, on one core, against the ratio
# stored for the newest commit (docs/results/data/speed-guard.json); fails 15 % above it. Run it
# alone on the machine before a change to the loop lands (`racf bench guard --store` after it
# lands); not in CI, whose machines are shared and noisy.
check-speed: $(STAMP)
	$(SINGLE_THREAD) $(if $(shell command -v taskset),taskset -c 0) $(VENV)/bin/racf bench guard --check

# Mutation testing of the link's code and the car's parts (cosmic-ray; tests/mutation/cosmic-ray.toml lists the modules):
# each mutant runs the tests that mirror its module. The session in outputs/mutation/ resumes where
# it stopped; changed modules, tests or configuration start it afresh. Prints the score over the
# non-equivalent mutants (goal 0.90) and every survivor not argued in tests/mutation/equivalent.toml.
# Not in CI: over an hour on one core. `make mutate MODULES="experiments/service/server.py ..."` runs a
# session of its own over some of them (two checkouts of one commit can share the cores that way).
mutate: $(STAMP)
	$(PY) -m pip install -qq "cosmic-ray>=8.7"
	$(SINGLE_THREAD) MUTATE_MODULES="$(MODULES)" $(PY) tests/mutation/session.py

# The documentation site into site/ (the reference pages are written from the code first).
# Serve it with: .venv/bin/mkdocs serve (http://127.0.0.1:8000), or open site/index.html.
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict
	@echo "site/ is built: open site/index.html, or serve it with $(VENV)/bin/mkdocs serve"

# The offline repair benchmark on the default dataset (collected first if missing).
bench: $(STAMP)
	test -f data/qcar2/dataset.parquet || $(VENV)/bin/racf collect
	$(VENV)/bin/racf bench offline

bench-sim: $(STAMP)
	$(VENV)/bin/racf bench sim

snapshot: $(STAMP)
	$(VENV)/bin/racf snapshot --out outputs/snapshot

trials: $(STAMP)
	$(VENV)/bin/racf trials --setting clean -n 30

bench-detector: $(STAMP)
	$(VENV)/bin/racf bench detector

clean:
	rm -rf $(VENV) outputs site build
