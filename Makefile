# racf: the two commands are `make demo` (main job) and `make test` (tests).
# Both create .venv and install what is missing: the CPU build of torch first (a newer
# or unpinned torch would pull several GB of CUDA packages), then racf and its deps.

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.racf-installed
TORCH := torch==2.13.0
export MUJOCO_GL ?= egl

.PHONY: demo test test-all check-slow bench bench-sim snapshot trials bench-detector clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet $(TORCH)
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

# The story at one stop sign: clean, patch attack, attack + ODCA (table, three .rrd, one PNG).
demo: $(STAMP)
	$(VENV)/bin/racf demo --out outputs/demo

# The default run leaves out the checks marked slow (Ray, kill-and-resume, bench-loop, full
# collection, PPO); `make test-all` runs everything, `make check-slow` only those.
test: $(STAMP)
	$(PY) -m pytest -q --durations=10

test-all: $(STAMP)
	$(PY) -m pytest -q -m "" --durations=10

check-slow: $(STAMP)
	$(PY) -m pytest -q -m slow --durations=10

# The offline repair benchmark on the default dataset (collected first if missing).
bench: $(STAMP)
	test -f data/qcar2/dataset.parquet || $(VENV)/bin/racf collect
	$(VENV)/bin/racf bench

bench-sim: $(STAMP)
	$(VENV)/bin/racf bench-sim

snapshot: $(STAMP)
	$(VENV)/bin/racf snapshot --out outputs/snapshot

trials: $(STAMP)
	$(VENV)/bin/racf trials --setting clean -n 30

bench-detector: $(STAMP)
	$(VENV)/bin/racf bench-detector

clean:
	rm -rf $(VENV) outputs
