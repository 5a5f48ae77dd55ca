# `make test` and `make run` install what is missing (Debian packages with apt-get, Python packages
# in .venv) and then run. Safe to repeat: each step is skipped when its result is already there.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
# the engines (with their recommended packages) and a one-node SLURM for the cluster tests (without);
# for the report's tests (without recommends): LaTeX to compile its tables (booktabs, graphicx, geometry),
# poppler-utils (pdftotext, pdffonts) to read them back, Chromium to load its page headless;
# binaries are checked by name and their packages installed if absent
ENGINE_DEBS := liggghts yade
SLURM_DEBS := munge slurmctld slurmd slurm-client
REPORT_DEBS := texlive-latex-base texlive-latex-recommended poppler-utils chromium
BINS := liggghts yade munged slurmctld slurmd sbatch pdflatex pdftotext pdffonts chromium

.PHONY: all deps debs venv test run bench flaky-check clean

all: test

debs:
	@missing=""; for b in $(BINS); do command -v $$b >/dev/null || missing="$$missing $$b"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages (missing:$$missing)"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $(ENGINE_DEBS) python3-venv && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $(SLURM_DEBS) $(REPORT_DEBS); \
	fi

$(VENV)/.installed: pyproject.toml
	@$(PYTHON) -m venv $(VENV) 2>/dev/null || { DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq python3-venv && $(PYTHON) -m venv $(VENV); }
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	# GrainLearning (calibration) pins numpy < 2 in its metadata but runs on numpy 2: measured, the same
	# posterior to every digit on 1.26.4 and 2.4 (docs/soils.md); installed without that pin, its
	# other needs (scipy, scikit-learn, matplotlib) come with the project
	$(PY) -m pip install -q --no-deps grainlearning==2.0.5
	touch $@

venv: $(VENV)/.installed

deps: debs venv

# the tests in parallel, one worker per core; tests sharing an expensive fixture, and the SLURM
# tests, are grouped onto one worker each (tests/conftest.py, xdist_group)
TEST_WORKERS ?= auto
test: deps
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadgroup

run: deps
	$(VENV)/bin/campaign run campaigns/quick.toml
	$(VENV)/bin/campaign report campaigns/quick.toml
	@echo "the campaign command is $(VENV)/bin/campaign: call it so, or first 'source $(VENV)/bin/activate'"

# each benchmark prints its own Markdown table for BENCHMARKS.md
bench: deps
	@for f in bench/bench_*.py; do echo "== $$f"; $(PY) $$f || exit 1; done

# the suite in fresh clones, 5 times idle then 5 times beside two LIGGGHTS runs: a verdict that
# depends on chance shows here (bench/flaky_check.py; results in BENCHMARKS.md)
flaky-check: deps
	$(PY) bench/flaky_check.py --runs 5
	$(PY) bench/flaky_check.py --runs 5 --load 2

clean:
	rm -rf $(VENV) runs .pytest_cache
